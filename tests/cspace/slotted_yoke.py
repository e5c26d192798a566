"""A Scotch yoke drawn as a user draws it in a model file: a crank pin (radius
``r`` at ``a`` from the axis) in a stadium slot (half width ``hw``, straight
part ``2 s``) of a sliding yoke (outline ``2 B`` by ``2 H``).  The tests of
user input, zones and jams share its drawing."""


def yoke_document(params, *, name="yoke", units="mm", window=40.0, drive=(0, "2*pi"),
                  q2_start=30.0, outline_names=None) -> dict:
    """The cspace-model document: ``params`` the parameter entries (a, r, hw,
    s, B, H), ``window`` the follower window's half span."""
    outline = {"polyline": [["-B", "-H"], ["B", "-H"], ["B", "H"], ["-B", "H"]]}
    if outline_names is not None:
        outline["names"] = list(outline_names)
    return {
        "format": "cspace-model", "version": 1, "name": name, "units": units,
        "parameters": params, "window": [0, "2*pi", -window, window],
        "drive": list(drive), "q2_start": [q2_start],
        "pairs": [{"name": "crank_yoke", "parts": [
            {"name": "crank", "axis": {"type": "rotation", "center": [0, 0]},
             "loops": [[{"type": "arc", "name": "pin", "center": ["a", 0], "radius": "r",
                         "start_angle": 0, "end_angle": "2*pi", "ccw": True}]]},
            {"name": "yoke", "axis": {"type": "translation", "direction": [1, 0],
                                      "origin": [0, 0]},
             "loops": [
                 outline,
                 [{"type": "line", "name": "slot.right", "start": ["hw", "s"],
                   "end": ["hw", "-s"]},
                  {"type": "arc", "name": "cap.bottom", "center": [0, "-s"], "radius": "hw",
                   "start_angle": 0, "end_angle": "-pi", "ccw": False},
                  {"type": "line", "name": "slot.left", "start": ["-hw", "-s"],
                   "end": ["-hw", "s"]},
                  {"type": "arc", "name": "cap.top", "center": [0, "s"], "radius": "hw",
                   "start_angle": "pi", "end_angle": 0, "ccw": False}]]}]}]}
