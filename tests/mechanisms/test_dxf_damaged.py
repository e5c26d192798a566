"""Damaged DXF drawings are FileFormatErrors naming the entity (issue 23, item 3)."""

import pytest

pytest.importorskip("ezdxf")

from cspace.errors import FileFormatError   # noqa: E402
from mechanisms.dxf import import_dxf      # noqa: E402
from synthesis.cli import main             # noqa: E402

PARTS = [{"layer": "A", "name": "a", "axis": {"type": "rotation", "center": [0, 0]}},
         {"layer": "B", "name": "b", "axis": {"type": "rotation", "center": [5, 0]}}]


def _drawing(tmp_path, first_entity: str):
    import ezdxf
    doc = ezdxf.new("R12")
    msp = doc.modelspace()
    msp.add_circle((0, 0), 1, dxfattribs={"layer": "A"})
    msp.add_circle((5, 0), 1, dxfattribs={"layer": "B"})
    src = tmp_path / "ok.dxf"
    doc.saveas(src)
    text = src.read_text()
    i = text.index("ENTITIES\n  0\n") + len("ENTITIES\n  0\n")
    p = tmp_path / "d.dxf"
    p.write_text(text[:i] + first_entity + "  0\n" + text[i:])
    return p


def test_entity_without_a_layer_is_a_file_format_error(tmp_path):
    p = _drawing(tmp_path, "FOOBAR\n  5\n99\n")
    with pytest.raises(FileFormatError, match=r"FOOBAR #99 has no layer"):
        import_dxf(p, parts=PARTS, units="mm")


def test_unknown_entity_keeps_its_raw_layer(tmp_path):
    p = _drawing(tmp_path, "FOOBAR\n  5\n99\n  8\nA\n")
    with pytest.raises(FileFormatError, match="FOOBAR is not supported on a part layer"):
        import_dxf(p, parts=PARTS, units="mm")
    # on another layer it is out of the way
    p = _drawing(tmp_path, "FOOBAR\n  5\n99\n  8\nNOTES\n")
    pair = import_dxf(p, parts=PARTS, units="mm")
    assert [pt.name for pt in pair.parts] == ["a", "b"]


def test_import_dxf_cli_one_line(tmp_path, capsys):
    p = _drawing(tmp_path, "FOOBAR\n  5\n99\n")
    rc = main(["import-dxf", str(p), "--out", str(tmp_path / "m.json"), "--units", "mm",
               "--part", "A:a:rotation:0,0", "--part", "B:b:rotation:5,0"])
    err = capsys.readouterr().err
    assert rc == 2 and "Traceback" not in err and "has no layer" in err


def test_drawing_without_a_model_space_is_a_file_format_error(tmp_path, monkeypatch):
    # found by the fuzz suite: ezdxf reads some damaged files whose model space
    # layout is missing, and raises KeyError('MODEL') when it is asked for
    import mechanisms.dxf as dxf
    p = _drawing(tmp_path, "FOOBAR\n  5\n99\n  8\nNOTES\n")
    real = dxf._read

    class NoModelSpace:
        def __init__(self, doc):
            self.header = doc.header

        def modelspace(self):
            raise KeyError("MODEL")

    monkeypatch.setattr(dxf, "_read", lambda path: NoModelSpace(real(path)))
    with pytest.raises(FileFormatError, match="model space cannot be read"):
        import_dxf(p, parts=PARTS, units="mm")
