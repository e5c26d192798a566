"""The batched margins of a built-in model computed in a fresh interpreter with
an environment switch set: what a kernel switch read at import time
(``CSPACE_FUSED``, ``CSPACE_NUMBA``) changes, compared across two runs."""

import json
import os
import subprocess
import sys

_SCRIPT = """
import json, sys
from mechanisms.models import BUILTIN
from cspace.defects import reference
from cspace.batch import {module} as switch
from cspace.batch.margins import defect_margins
from synthesis.verify import box_samples
m = BUILTIN[{model!r}]()
ref = reference(m, "fast")
U = box_samples(m.nominal, m.tol, {n}, seed=2)
mb = defect_margins(m, U, ref, fallback=False)
print(json.dumps({{"enabled": switch.ENABLED, "defective": mb.defective.tolist(),
                  "certified": mb.certified.tolist(), "margins": mb.margins().tolist()}}))
"""


def batch_in_subprocess(module: str, model: str, n: int, env: dict) -> dict:
    """``defect_margins`` (no fall-back) of ``n`` box samples (seed 2) of the
    built-in ``model`` in a new interpreter with ``env`` added to the
    environment: ``{"enabled": cspace.batch.<module>.ENABLED, "defective",
    "certified", "margins"}`` (lists)."""
    p = subprocess.run([sys.executable, "-c", _SCRIPT.format(module=module, model=model, n=n)],
                       env=dict(os.environ, **env), capture_output=True, text=True, timeout=600)
    assert p.returncode == 0, p.stderr
    return json.loads(p.stdout.strip().splitlines()[-1])
