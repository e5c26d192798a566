"""The checkpoint file of ``cspace-tol synthesize``: its content hash.

A checkpoint is the JSON of :meth:`SynthesisState.to_dict` plus one key,
``"sha256"``: the SHA-256 of the rest of the document in a canonical form (keys
sorted, no spaces, floats by ``repr``, which JSON reads back bit for bit).  A
checkpoint whose content no longer matches its hash (a digit changed by hand, a
disk error that left valid JSON) is refused with a
:class:`~cspace.errors.FileFormatError` that says so, and is left as it is.

The hash guards against damage, not against a deliberate edit: anyone can
recompute it.  A checkpoint without ``"sha256"`` was written before the hash
was kept; it is read with the content checks of :meth:`SynthesisState.from_dict`
only (:func:`read_checkpoint` reports it through ``verified``).
"""

from __future__ import annotations

import hashlib
import json

from cspace.errors import FileFormatError
from cspace.io import atomic_write, dumps, load_json

from .result import SynthesisState

__all__ = ["content_hash", "checkpoint_text", "write_checkpoint", "read_checkpoint",
           "HASH_KEY"]

#: The key of the content hash in a checkpoint document.
HASH_KEY = "sha256"


def content_hash(doc: dict) -> str:
    """SHA-256 (hex) of a checkpoint document without its ``HASH_KEY``."""
    body = {k: v for k, v in doc.items() if k != HASH_KEY}
    # through JSON once so that numpy values and tuples hash as they are read back
    canon = json.dumps(json.loads(dumps(body)), sort_keys=True, separators=(",", ":"),
                       allow_nan=False)
    return hashlib.sha256(canon.encode("utf-8")).hexdigest()


def checkpoint_text(state: SynthesisState) -> str:
    """The checkpoint file's text: the state's JSON with its content hash."""
    d = state.to_dict()
    d[HASH_KEY] = content_hash(d)
    return dumps(d)


def write_checkpoint(path, state: SynthesisState):
    """Write ``state`` to ``path`` atomically, with its content hash."""
    return atomic_write(path, checkpoint_text(state))


def read_checkpoint(path) -> tuple[SynthesisState, bool]:
    """The state in a checkpoint file and whether its hash was verified.

    Returns
    -------
    state : SynthesisState
    verified : bool
        False for a checkpoint written before hashes were kept (no ``"sha256"``).

    Raises
    ------
    FileFormatError
        Not a checkpoint, damaged content, or content that does not match its
        hash.
    """
    doc = load_json(path)
    state = SynthesisState.from_dict(doc, path=str(path))
    if not isinstance(doc, dict) or HASH_KEY not in doc:
        return state, False
    stored = doc[HASH_KEY]
    if not isinstance(stored, str) or len(stored) != 64:
        raise FileFormatError(f"damaged checkpoint: {HASH_KEY!r} must be 64 hex digits, got "
                              f"{str(stored)[:70]!r}", path=str(path))
    actual = content_hash(doc)
    if stored.lower() != actual:
        raise FileFormatError(f"damaged checkpoint: its content does not match its "
                              f"{HASH_KEY} (stored {stored[:12]}..., content gives "
                              f"{actual[:12]}...); the file was changed after it was written. "
                              f"It is left as it is: restore it, or start over with --fresh",
                              path=str(path))
    return state, True
