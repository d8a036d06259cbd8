"""The Python tutorial's script (docs/tutorial/settling_box.py) gives what
docs/tutorial/python.md says, which is what `efgdem run` gives for the same
scenario file (tests/docs_tutorial.rs checks that side)."""

import runpy
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def test_python_tutorial_script(capsys, monkeypatch):
    monkeypatch.setattr(sys, "argv", ["settling_box.py"])
    runpy.run_path(str(ROOT / "docs" / "tutorial" / "settling_box.py"), run_name="__main__")
    out = capsys.readouterr().out
    page = (ROOT / "docs" / "tutorial" / "python.md").read_text()
    for line in ("contacts: 528", "floor force: -605.8 N", "highest grain top: 0.107 m"):
        assert line in out, out
        assert f"`{line}`" in page, line
