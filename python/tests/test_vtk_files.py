"""The ParaView files of `efgdem run`, read by readers that are not ours.

VTK's own XML readers (the `vtk` wheel: the readers ParaView uses) read
every `.vtp` and `.vtu` of a small coupled run (Example 1) and of a small
granular run (a settling box with walls), in each of the three
`vtk_format`s; meshio, a separate pure-Python implementation of the same
format, reads every `.vtu` too (meshio has no PolyData `.vtp` reader, so it
cannot be the only reader). The arrays are checked against `history.csv`,
`summary.json` and `discs_final.csv`, which are written by other code.
"""

import csv
import json
import os
import re
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest

vtk = pytest.importorskip("vtk")
meshio = pytest.importorskip("meshio")
from vtk.util.numpy_support import vtk_to_numpy  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]
EXAMPLE1 = ROOT / "examples" / "paper_cantilever_disc.toml"
BOX = ROOT / "docs" / "tutorial" / "01_settling_box.toml"
FORMATS = ["binary", "binary_uncompressed", "ascii"]


def cli():
    for p in (ROOT / "target" / "release" / "efgdem", shutil.which("efgdem")):
        if p and Path(p).exists():
            return str(p)
    pytest.skip("no efgdem binary (cargo build --release)")


def run(text, tmp_path, tag):
    sc = tmp_path / f"{tag}.toml"
    sc.write_text(text)
    out = tmp_path / tag
    subprocess.run([cli(), "run", str(sc), "-o", str(out), "-q"], check=True)
    return out


def set_output(text, **fields):
    """`text` with its [output] section replaced by `fields`."""
    text = re.sub(r"\[output\][^\[]*", "", text)
    body = "\n".join(f"{k} = {json.dumps(v)}" for k, v in fields.items())
    return text + f"\n[output]\n{body}\n"


def history(out):
    with open(out / "history.csv") as f:
        return {int(r["step"]): {k: float(v) for k, v in r.items()} for r in csv.DictReader(f)}


def series(out, name):
    """(step, time, path) of each entry of `name`.pvd."""
    text = (out / f"{name}.pvd").read_text()
    assert text.rstrip().endswith("</VTKFile>")
    rows = re.findall(r'timestep="([^"]+)" part="0" file="([^"]+)"', text)
    return [(int(re.search(r"_(\d{7})\.vt[pu]$", f).group(1)), float(t), out / f) for t, f in rows]


def read_vtk(path):
    """Points, point data and cell data (name -> array) by VTK's reader."""
    r = vtk.vtkXMLPolyDataReader() if path.suffix == ".vtp" else vtk.vtkXMLUnstructuredGridReader()
    r.SetFileName(str(path))
    r.Update()
    assert r.GetErrorCode() == 0, path
    d = r.GetOutput()
    pts = d.GetPoints()
    xyz = vtk_to_numpy(pts.GetData()) if pts is not None else np.zeros((0, 3))

    def arrays(fd):
        out = {}
        for k in range(fd.GetNumberOfArrays()):
            a = fd.GetArray(k)
            v = vtk_to_numpy(a)
            out[a.GetName()] = v if a.GetNumberOfTuples() else v.reshape(0, a.GetNumberOfComponents())
        return out

    pd = arrays(d.GetPointData())
    gi = d.GetPointData().GetGlobalIds()
    return xyz, pd, arrays(d.GetCellData()), (gi.GetName() if gi else None), d


def test_coupled_run_files_match_history(tmp_path):
    text = EXAMPLE1.read_text().replace("end_time = 0.2", "end_time = 0.02")
    outs = {}
    for fmt in FORMATS:
        outs[fmt] = run(set_output(text, every=10, vtk_every=30, vtk_format=fmt), tmp_path, fmt)
    out = outs["binary"]
    h = history(out)
    summary = json.loads((out / "summary.json").read_text())
    last = summary["last_step"]
    assert last == 200
    sets = {n: series(out, n) for n in ("discs", "contacts", "beam")}
    for n, s in sets.items():
        # every 30 steps and the last one
        assert [e[0] for e in s] == [0, 30, 60, 90, 120, 150, 180, 200], n
    for (step, t, disc_f), (_, tc, con_f), (_, tb, beam_f) in zip(*sets.values()):
        assert t == tc == tb == h[step]["t"]
        row = h[step]
        # the disc, by VTK's reader
        xyz, pd, _, gid, _ = read_vtk(disc_f)
        assert gid == "id" and pd["id"].tolist() == [1]
        assert pd["radius"].tolist() == [0.05] and pd["diameter"].tolist() == [0.1]
        assert pd["velocity"].shape == (1, 3) and pd["force"].shape == (1, 3)
        u = xyz[0, :2] - [0.999999, 0.15]
        assert u == pytest.approx([row["disc_ux"], row["disc_uy"]], rel=1e-9, abs=1e-15)
        # the beam: deformed points, displacement as a 3-vector
        xyz, pd, _, _, grid = read_vtk(beam_f)
        assert grid.GetNumberOfPoints() == 80 and grid.GetNumberOfCells() == 57
        ref = xyz - pd["displacement"]
        assert np.allclose(pd["displacement"][:, 2], 0.0) and np.allclose(ref[:, 2], 0.0)
        tip = np.argmin(np.hypot(ref[:, 0] - 1.0, ref[:, 1] - 0.1))
        assert np.hypot(ref[tip, 0] - 1.0, ref[tip, 1] - 0.1) < 1e-12
        scale = max(1e-12, np.abs(pd["displacement"]).max())
        assert abs(pd["displacement"][tip, 0] - row["tip_ux"]) < 1e-9 * scale
        assert abs(pd["displacement"][tip, 1] - row["tip_uy"]) < 1e-9 * scale
        s = pd["stress"]
        assert s.shape == (80, 6)
        assert np.all(s[:, 2] == 0) and np.all(s[:, 4:] == 0)  # plane stress
        assert np.array_equal(pd["sigma_xx"], s[:, 0]) and np.array_equal(pd["sigma_xy"], s[:, 3])
        vm = np.sqrt(0.5 * ((s[:, 0] - s[:, 1]) ** 2 + s[:, 1] ** 2 + s[:, 0] ** 2) + 3 * s[:, 3] ** 2)
        assert np.allclose(pd["von_mises"], vm, rtol=1e-12, atol=1e-12 * max(vm.max(), 1e-300))
        e = pd["strain"]
        E, nu = 2.1e8, 0.3
        assert np.allclose(e[:, 0], (s[:, 0] - nu * s[:, 1]) / E, rtol=1e-9, atol=1e-9 * np.abs(e).max() + 1e-300)
        assert np.allclose(e[:, 2], -nu * (s[:, 0] + s[:, 1]) / E, rtol=1e-9, atol=1e-9 * np.abs(e).max() + 1e-300)
        # meshio reads the same grid
        m = meshio.read(beam_f)
        assert np.array_equal(m.points, xyz)
        for k, v in pd.items():
            assert np.array_equal(np.asarray(m.point_data[k]).reshape(v.shape), v), k
        assert m.cells[0].type == "quad" and len(m.cells[0].data) == 57
        # contacts: the disc on the beam; the sum of `fn` is history's contact_fn
        xyz, _, cd, _, poly = read_vtk(con_f)
        assert poly.GetNumberOfLines() == len(cd["kind"])
        assert set(cd["kind"].tolist()) <= {2}
        assert cd["fn"].sum() == pytest.approx(row["contact_fn"], rel=1e-12, abs=1e-12)
        if len(cd["kind"]):
            assert cd["disc"].tolist() == [1] * len(cd["kind"]) and set(cd["other"].tolist()) == {1}
            # the normal force pushes the disc back from the contact point
            # (along the line to it, up to the body's turn within the step)
            nf = cd["normal_force"]
            assert np.allclose(np.linalg.norm(nf, axis=1), cd["fn"], rtol=1e-12)
            d = xyz[1::2] - xyz[0::2]
            along = np.einsum("ij,ij->i", nf, d / np.linalg.norm(d, axis=1)[:, None])
            assert np.allclose(along, -cd["fn"], rtol=1e-3)
            assert np.allclose(np.linalg.norm(cd["tangential_force"], axis=1), cd["ft"])
    assert any(len(read_vtk(f)[2]["kind"]) for _, _, f in sets["contacts"][1:])
    # the three formats hold the same numbers
    for fmt in FORMATS[1:]:
        for name in ("discs", "contacts", "beam"):
            for (_, _, a), (_, _, b) in zip(series(out, name), series(outs[fmt], name)):
                A, B = read_vtk(a), read_vtk(b)
                assert np.array_equal(A[0], B[0])
                for x, y in ((A[1], B[1]), (A[2], B[2])):
                    assert x.keys() == y.keys()
                    for k in x:
                        assert np.array_equal(x[k], y[k]), (fmt, name, k)


def test_granular_run_files_match_history(tmp_path):
    text = BOX.read_text().replace("end_time = 1.0 ", "end_time = 0.4 ")
    out = run(set_output(text, every=100, vtk_every=500), tmp_path, "box")
    h = history(out)
    summary = json.loads((out / "summary.json").read_text())
    last = summary["last_step"]
    sets = {n: series(out, n) for n in ("discs", "contacts", "walls")}
    steps = [e[0] for e in sets["discs"]]
    assert steps[0] == 0 and steps[-1] == last and all(s % 500 == 0 for s in steps[:-1])
    n = summary["discs"]
    xyz0 = read_vtk(sets["discs"][0][2])[0]
    for (step, t, disc_f), (_, _, con_f), (_, _, wall_f) in zip(*sets.values()):
        xyz, pd, _, gid, _ = read_vtk(disc_f)
        # displacement since t = 0 (the first frame), by id
        assert np.array_equal(pd["displacement"], xyz - xyz0)
        assert gid == "id" and np.array_equal(pd["id"], np.arange(1, n + 1))
        assert np.all((pd["radius"] >= 0.004) & (pd["radius"] <= 0.006))
        assert np.array_equal(pd["diameter"], 2 * pd["radius"])
        _, _, cd, _, _ = read_vtk(con_f)
        kinds = cd["kind"].tolist()
        # the coordination numbers count each contact at its discs
        z = np.zeros(n + 1, dtype=int)
        np.add.at(z, cd["disc"], 1)
        np.add.at(z, cd["other"][cd["kind"] == 0], 1)
        assert np.array_equal(pd["coordination"], z[1:])
        if step in h:
            assert h[step]["t"] == t
            assert kinds.count(0) + kinds.count(1) == h[step]["contacts"]
        wxyz, _, wd, _, _ = read_vtk(wall_f)
        assert wd["wall"].tolist() == [1, 2, 3]  # numbered from 1, as discs
        if step in h:
            assert wd["force"][0, 1] == h[step]["floor_fy"]
    # the last frame: summary.json and discs_final.csv
    xyz, pd, _, _, _ = read_vtk(sets["discs"][-1][2])
    final = np.loadtxt(out / "discs_final.csv", delimiter=",", skiprows=1)
    assert np.array_equal(xyz[:, :2], final[:, :2]) and np.array_equal(pd["radius"], final[:, 2])
    assert np.array_equal(final[:, 3], pd["id"])  # x,y,r,id: the same numbers
    _, _, cd, _, _ = read_vtk(sets["contacts"][-1][2])
    kinds = cd["kind"].tolist()
    assert kinds.count(0) == summary["contacts"]["disc_disc"]
    assert kinds.count(1) == summary["contacts"]["disc_wall"]
    wxyz, _, wd, _, _ = read_vtk(sets["walls"][-1][2])
    for k, w in enumerate(summary["wall_forces"]):
        assert wd["force"][k].tolist() == [*w["force"], 0.0]
        assert wxyz[2 * k, :2].tolist() == w["position_from"]


def test_view_script_renders(tmp_path):
    """`efgdem view OUT --no-open` writes OUT/view.py; where ParaView is
    installed, pvbatch renders it (the discs, the beam and the contact)."""
    text = EXAMPLE1.read_text().replace("end_time = 0.2", "end_time = 0.02")
    out = run(set_output(text, every=10, vtk_every=50), tmp_path, "ex1")
    o = subprocess.run([cli(), "view", str(out), "--no-open"], capture_output=True, text=True)
    assert o.returncode == 0, o.stderr
    script = out / "view.py"
    compile(script.read_text(), str(script), "exec")
    empty = tmp_path / "empty"
    empty.mkdir()
    o = subprocess.run([cli(), "view", str(empty), "--no-open"], capture_output=True, text=True)
    assert o.returncode != 0 and "vtk_every" in o.stderr
    if shutil.which("pvbatch") is None:
        pytest.skip("no pvbatch (ParaView) on PATH")
    if not (os.environ.get("DISPLAY") or shutil.which("Xvfb")):
        pytest.skip("no display and no Xvfb")
    # `efgdem view --screenshot` renders on a virtual display of its own
    # when there is none
    o = subprocess.run([cli(), "view", str(out), "--screenshot", str(tmp_path / "view.png"),
                        "--size", "640", "360"], capture_output=True, text=True, timeout=300)
    assert o.returncode == 0, o.stderr[-3000:]
    Image = pytest.importorskip("PIL.Image")
    im = np.asarray(Image.open(tmp_path / "view.png").convert("RGB")).astype(int)
    assert im.shape == (360, 640, 3)
    # the view is mostly white background, with the coloured beam and disc
    coloured = (np.abs(im - im.mean(axis=2, keepdims=True)).max(axis=2) > 40).mean()
    assert 0.05 < coloured < 0.8, coloured

    def sag(png):
        """How much lower (pixels) the beam's bottom edge is near its tip
        than near its clamped end (above the colour bars)."""
        im = np.asarray(Image.open(png).convert("RGB")).astype(int)[:280]
        bottom = [np.nonzero((im[:, a:a + 40].sum(axis=2) < 700).any(axis=1))[0].max()
                  for a in (60, 540)]
        return bottom[1] - bottom[0]

    # --warp: the tip deflection (1.5 mm, a pixel) drawn 50 times larger
    o = subprocess.run([cli(), "view", str(out), "--screenshot", str(tmp_path / "warp.png"),
                        "--size", "640", "360", "--warp", "50"],
                       capture_output=True, text=True, timeout=300)
    assert o.returncode == 0, o.stderr[-3000:]
    drop = (sag(tmp_path / "view.png"), sag(tmp_path / "warp.png"))
    assert drop[0] <= 2 and 25 < drop[1] < 70, drop

    def colours(args):
        """{title: (low, high)} of the colour bars `efgdem view --screenshot`
        reports for the image it renders with `args`."""
        o = subprocess.run([cli(), "view", str(out), "--screenshot", str(tmp_path / "c.png"),
                            "--size", "320", "180", *args], capture_output=True, text=True, timeout=300)
        assert o.returncode == 0, o.stderr[-3000:]
        bars = [line.split(": ") for line in o.stdout.splitlines() if line.startswith("colours: ")]
        return {b[1]: tuple(float(v) for v in b[2].split(" to ")) for b in bars}

    # colour ranges over the whole series (default) stay put when an early
    # frame is shown; --range frame takes the frame's own; the discs' range
    # ends at the 99th percentile of their speeds
    beam = [read_vtk(f)[1]["von_mises"] for _, _, f in series(out, "beam")]
    speeds = np.concatenate([np.linalg.norm(read_vtk(f)[1]["velocity"], axis=1)
                             for _, _, f in series(out, "discs")])
    t1, k1 = series(out, "beam")[1][1], 1
    stress, disc = "von Mises stress [Pa]", "disc speed [m/s], 99% below"
    whole = colours(["--time", str(t1)])
    assert whole[stress] == pytest.approx((min(b.min() for b in beam), max(b.max() for b in beam)), rel=1e-8)
    assert whole[disc] == pytest.approx((0.0, np.percentile(speeds, 99.0)), rel=1e-8)
    own = colours(["--time", str(t1), "--range", "frame", "--percentile", "100"])
    assert own[stress] == pytest.approx((beam[k1].min(), beam[k1].max()), rel=1e-8)
    # the early frame's stresses are a part of the series' range
    assert own[stress][1] < 0.8 * whole[stress][1], (own, whole)
    speed1 = np.linalg.norm(read_vtk(series(out, "discs")[k1][2])[1]["velocity"], axis=1).max()
    assert own["disc speed [m/s]"] == pytest.approx((0.0, speed1), rel=1e-8)
    # --region: the ranges are those of the points in it (the clamped part
    # of the beam, away from the disc's impact near the tip)
    part = colours(["--region", "-0.1", "-0.1", "0.7", "0.3", "--percentile", "100"])

    def clamped(f):
        xyz, pd, _, _, _ = read_vtk(f)
        return pd["von_mises"][xyz[:, 0] <= 0.7]

    v = np.concatenate([clamped(f) for _, _, f in series(out, "beam")])
    assert part[stress] == pytest.approx((v.min(), v.max()), rel=1e-8)
    assert part[stress][1] < 0.99 * whole[stress][1], (part, whole)

    def grid_pixels(args):
        """Pixels of the body's grid-line grey (above the colour bars) in
        the 640 × 360 image rendered with `args`."""
        png = tmp_path / "edges.png"
        o = subprocess.run([cli(), "view", str(out), "--screenshot", str(png), "--size", "640", "360",
                            *args], capture_output=True, text=True, timeout=300)
        assert o.returncode == 0, o.stderr[-3000:]
        im = np.asarray(Image.open(png).convert("RGB")).astype(int)[:270]
        return int((np.abs(im - 89).max(axis=2) <= 6).sum())

    # body grid lines: off, on, and `auto`: on where a cell is 6 pixels or
    # wider (the beam's cells, ~0.06 m, are ~30 px on the whole scene), off
    # where they are narrower (~3.5 px in a 9 m wide --region)
    off, on = grid_pixels(["--edges", "off"]), grid_pixels(["--edges", "on"])
    assert off < 50 and on > 150, (off, on)
    assert grid_pixels([]) == on
    far = ["--region", "-4", "-2", "5", "2.5"]
    small = [grid_pixels(far + e) for e in ([], ["--edges", "on"], ["--edges", "off"])]
    assert small[0] == small[2] < small[1], small
