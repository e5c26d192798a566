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


def _two_discs():
    """A drawing in mm with a disc on layer A and one on layer B (R2010)."""
    import ezdxf
    doc = ezdxf.new()
    doc.header["$INSUNITS"] = 4
    msp = doc.modelspace()
    msp.add_circle((0, 0), 1, dxfattribs={"layer": "A"})
    msp.add_circle((5, 0), 1, dxfattribs={"layer": "B"})
    return doc, msp


def test_a_block_holding_part_geometry_is_refused(tmp_path):
    doc, msp = _two_discs()
    # a hole of part A drawn in a block, the block placed on layer 0
    blk = doc.blocks.new(name="HOLE")
    blk.add_circle((0, 0), 0.3, dxfattribs={"layer": "A"})
    msp.add_blockref("HOLE", (0, 0), dxfattribs={"layer": "0"})
    p = tmp_path / "block.dxf"
    doc.saveas(p)
    with pytest.raises(FileFormatError, match=r"block 'HOLE' \(INSERT #\w+ on layer '0'\) holds "
                                              r"entities on the part layer\(s\) \['A'\]; blocks "
                                              r"are not read.*EXPLODE"):
        import_dxf(p, parts=PARTS, units="mm")
    # a block on no part's layer (a title block) is no concern
    doc2, m2 = _two_discs()
    tb = doc2.blocks.new(name="TITLE")
    tb.add_line((0, 0), (1, 0), dxfattribs={"layer": "FRAME"})
    m2.add_blockref("TITLE", (20, 20), dxfattribs={"layer": "0"})
    p2 = tmp_path / "title.dxf"
    doc2.saveas(p2)
    assert import_dxf(p2, parts=PARTS, units="mm") is not None


def test_two_parts_of_one_name_are_refused(tmp_path):
    from cspace.errors import InputError
    doc, _ = _two_discs()
    p = tmp_path / "two.dxf"
    doc.saveas(p)
    same = [dict(PARTS[0]), dict(PARTS[1], name="a")]
    with pytest.raises(InputError, match="the driver and the follower need different names, "
                                         "both are 'a'"):
        import_dxf(p, parts=same, units="mm")


def test_two_parts_on_one_layer_are_refused(tmp_path):
    """One layer for both parts made a pair whose driver and follower were the
    same profile; layers match case-insensitively."""
    from cspace.errors import InputError
    doc, _ = _two_discs()
    p = tmp_path / "one.dxf"
    doc.saveas(p)
    same = [dict(PARTS[0]), dict(PARTS[1], layer=PARTS[0]["layer"].swapcase())]
    with pytest.raises(InputError, match="both read from layer .*a layer of its own"):
        import_dxf(p, parts=same, units="mm")


def test_a_duplicated_entity_is_named_as_a_duplicate(tmp_path):
    """A copy pasted in place (the same line twice, the same circle twice) was
    refused as segment ends or loops meeting at a point; the message names
    both entities as a duplicate."""
    import ezdxf
    for dup in ("line", "circle"):
        doc = ezdxf.new("R2010")
        doc.header["$INSUNITS"] = 4
        msp = doc.modelspace()
        pts = [(0, 0), (4, 0), (4, 3), (0, 3)]
        for a, b in zip(pts, pts[1:] + pts[:1]):
            msp.add_line(a, b, dxfattribs={"layer": "A"})
        if dup == "line":
            msp.add_line((4, 0), (4, 3), dxfattribs={"layer": "A"})
        msp.add_circle((10, 0), 1, dxfattribs={"layer": "B"})
        if dup == "circle":
            msp.add_circle((10, 0), 1, dxfattribs={"layer": "B"})
        p = tmp_path / f"{dup}.dxf"
        doc.saveas(p)
        what = "line from .*" if dup == "line" else r"circle about \(10, 0\), radius 1"
        with pytest.raises(FileFormatError, match=rf"#\w+: the same {what} as \w+ #\w+ "
                                                  r"\(a duplicate"):
            import_dxf(p, parts=PARTS, units="mm")
