"""Tests of the efgdem Python module (build it first: `maturin develop
--release -m python/Cargo.toml`, then `pytest python/tests`)."""

import gc
import os
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import efgdem

ROOT = Path(__file__).resolve().parents[2]
EXAMPLE1 = ROOT / "examples" / "paper_cantilever_disc.toml"

# Three discs on a floor between two walls; discs 1 and 2 overlap at t = 0.
BOX_TOML = """\
[simulation]
dt = 1.0e-4
steps = 400
gravity = [0.0, -9.81]

[[material]]
name = "grain"
density = 2000.0
kn = 1.0e5
ks = 5.0e4
friction = 0.4

[granular]
material = "grain"
thickness = 0.1
discs = [[0.10, 0.05, 0.05], [0.195, 0.05, 0.05], [0.15, 0.2, 0.04]]
damping = { kind = "contact-viscous", beta = 1.0e-4 }
allow_overlap = true  # discs 1 and 2 start pressed together on purpose

[[wall]]
name = "floor"
from = [0.0, 0.0]
to = [0.4, 0.0]

[[wall]]
name = "left"
from = [0.0, 0.0]
to = [0.0, 0.4]

[[probe]]
name = "y3"
disc = 3
quantity = "y"
"""

BOX_DICT = {
    "simulation": {"dt": 1.0e-4, "steps": 400, "gravity": [0.0, -9.81]},
    "material": [
        {"name": "grain", "density": 2000.0, "kn": 1.0e5, "ks": 5.0e4, "friction": 0.4}
    ],
    "granular": {
        "material": "grain",
        "thickness": 0.1,
        "discs": [[0.10, 0.05, 0.05], [0.195, 0.05, 0.05], [0.15, 0.2, 0.04]],
        "damping": {"kind": "contact-viscous", "beta": 1.0e-4},
        "allow_overlap": True,
    },
    "wall": [
        {"name": "floor", "from": [0.0, 0.0], "to": [0.4, 0.0]},
        {"name": "left", "from": [0.0, 0.0], "to": [0.0, 0.4]},
    ],
    "probe": [{"name": "y3", "disc": 3, "quantity": "y"}],
}


def settling(count=300, seed=5):
    """A loose random packing in a closed box (the DEM renumbers its slots
    as the discs fall)."""
    walls = [((0, 0), (40, 0)), ((40, 0), (40, 60)), ((40, 60), (0, 60)), ((0, 60), (0, 0))]
    return {
        "simulation": {"dt": 4.0e-4, "steps": 3000, "gravity": [0.0, -9.81]},
        "material": [{"name": "g", "density": 1.0, "kn": 1.0e6, "ks": 1.0e6, "friction": 0.5}],
        "granular": {
            "material": "g",
            "discs": {"generate": "random", "box": [[0, 0], [40, 60]],
                      "radius": [0.8, 1.2], "count": count, "seed": seed},
            "damping": {"kind": "critical-ratio", "zeta": 0.2},
        },
        "wall": [{"name": f"w{k}", "from": list(a), "to": list(b)}
                 for k, (a, b) in enumerate(walls)],
    }


@pytest.fixture
def box_file(tmp_path):
    p = tmp_path / "box.toml"
    p.write_text(BOX_TOML)
    return p


def load_toml(path):
    tomllib = pytest.importorskip("tomllib")
    with open(path, "rb") as f:
        return tomllib.load(f)


# --- from_scenario and from_dict -------------------------------------------


def test_from_scenario_equals_from_dict_bitwise(box_file):
    a = efgdem.Model.from_scenario(box_file)
    b = efgdem.Model.from_dict(BOX_DICT)
    for m in (a, b):
        m.step(150)
        m.step()
        m.run(0.03)
    assert a.step_count == b.step_count == 300
    assert a.time == b.time
    for f in ("disc_positions", "disc_velocities", "disc_spins", "disc_forces"):
        x, y = getattr(a, f)(), getattr(b, f)()
        assert x.tobytes() == y.tobytes(), f
    assert a.contacts().tobytes() == b.contacts().tobytes()
    assert a.probe("y3") == b.probe("y3")


def test_example1_from_scenario_equals_from_dict_bitwise():
    a = efgdem.Model.from_scenario(EXAMPLE1)
    b = efgdem.Model.from_dict(load_toml(EXAMPLE1), base_dir=EXAMPLE1.parent)
    assert a.kind == b.kind == "coupled"
    a.step(120)
    b.step(120)
    assert a.disc_positions().tobytes() == b.disc_positions().tobytes()
    xa, ua = a.body_displacement("beam")
    xb, ub = b.body_displacement(0)
    assert xa.tobytes() == xb.tobytes() and ua.tobytes() == ub.tobytes()
    assert a.contacts().tobytes() == b.contacts().tobytes()
    assert a.probe("tip_uy") == b.probe("tip_uy")


def test_dict_accepts_tuples_numpy_values_and_none():
    d = {
        "simulation": {"dt": np.float64(1.0e-4), "steps": np.int64(400),
                       "gravity": (0.0, -9.81), "threads": None},
        "material": BOX_DICT["material"],
        "granular": dict(BOX_DICT["granular"],
                         discs=np.array(BOX_DICT["granular"]["discs"])),
        "wall": BOX_DICT["wall"],
    }
    a = efgdem.Model.from_dict(d)
    b = efgdem.Model.from_dict(BOX_DICT)
    a.step(50)
    b.step(50)
    assert a.disc_positions().tobytes() == b.disc_positions().tobytes()
    assert "[[material]]" in efgdem.scenario_toml(BOX_DICT)


def test_results_do_not_depend_on_threads():
    a = efgdem.Model.from_dict(settling(), threads=1)
    b = efgdem.Model.from_dict(settling(), threads=2)
    a.step(500)
    b.step(500)
    assert a.disc_positions().tobytes() == b.disc_positions().tobytes()


# --- state as numpy arrays --------------------------------------------------


def test_state_arrays_shapes_dtypes_and_initial_values(box_file):
    m = efgdem.Model.from_scenario(box_file)
    discs = np.array(BOX_DICT["granular"]["discs"])
    assert m.kind == "granular" and m.n_discs == 3 and m.body_names() == []
    assert (m.dt, m.steps, m.step_count, m.time) == (1.0e-4, 400, 0, 0.0)
    pos = m.disc_positions()
    assert pos.shape == (3, 2) and pos.dtype == np.float64 and pos.flags.c_contiguous
    assert np.array_equal(pos, discs[:, :2])  # id order: row i is disc i
    assert np.array_equal(m.disc_radii(), discs[:, 2])
    for f in ("disc_velocities", "disc_forces"):
        a = getattr(m, f)()
        assert a.shape == (3, 2) and a.dtype == np.float64 and not a.any()
    for f in ("disc_spins", "disc_rotations"):
        a = getattr(m, f)()
        assert a.shape == (3,) and a.dtype == np.float64 and not a.any()
    # ids are the files' numbers (from 1), indices the rows (from 0)
    ids = m.disc_ids()
    assert ids.dtype == np.uint32 and sorted(ids) == [1, 2, 3]
    assert np.array_equal(m.disc_indices(), ids - 1)
    assert m.probe_names() == ["y3"] and m.probe("y3") == 0.2
    # copies are snapshots
    pos[:] = 0.0
    assert np.array_equal(m.disc_positions(), discs[:, :2])
    m.step(10)
    assert (pos == 0.0).all() and m.disc_positions()[2, 1] < 0.2
    assert m.probe("y3") == m.disc_positions()[2, 1]


def test_contacts_structured_array(box_file):
    m = efgdem.Model.from_scenario(box_file)
    m.step()
    c = m.contacts()
    assert c.dtype.names == ("kind", "disc", "other", "disc_index", "other_index", "x", "y",
                             "nx", "ny", "overlap", "fn_elastic", "fn_total", "fs")
    assert c.dtype["kind"] == np.uint8 and c.dtype["disc"] == np.uint32
    assert c.dtype["x"] == np.float64
    # numbers as in the files (from 1), indices from 0
    assert np.array_equal(c["disc"], c["disc_index"] + 1)
    assert np.array_equal(c["other"], c["other_index"] + 1)
    # discs 1 and 2 overlap, both touch the floor (wall 1)
    dd = c[c["kind"] == efgdem.CONTACT_DISC_DISC]
    assert len(dd) == 1 and {int(dd["disc"][0]), int(dd["other"][0])} == {1, 2}
    pos, r = m.disc_positions(), m.disc_radii()
    d = np.linalg.norm(pos[1] - pos[0])
    assert dd["overlap"][0] == pytest.approx(r[0] + r[1] - d, rel=1e-12)
    assert dd["fn_elastic"][0] == pytest.approx(1.0e5 * dd["overlap"][0], rel=1e-12)
    n = np.array([dd["nx"][0], dd["ny"][0]])
    assert np.linalg.norm(n) == pytest.approx(1.0)
    dw = c[c["kind"] == efgdem.CONTACT_DISC_WALL]
    assert sorted(zip(dw["disc"].tolist(), dw["other"].tolist())) == [(1, 1), (2, 1)]
    assert (c["fn_elastic"] > 0).all() and (c["overlap"] > 0).all()
    assert len(efgdem.Model.from_dict(settling()).contacts()) == 0


def test_views_are_zero_copy_read_only_and_live():
    m = efgdem.Model.from_dict(settling())
    v = m.disc_views()
    assert set(v) == {"pos", "vel", "force", "radius", "omega", "theta", "index"}
    assert v["pos"].shape == (300, 2) and v["index"].dtype == np.uint32
    for a in v.values():
        assert not a.flags.writeable and not a.flags.owndata
        with pytest.raises(ValueError):
            a[0] = 0
    before = v["pos"].copy()
    # the discs fall: the slots are renumbered several times on the way
    for _ in range(6):
        m.step(500)
        order = np.argsort(v["index"])
        assert np.array_equal(v["pos"][order], m.disc_positions())
        assert np.array_equal(v["vel"][order], m.disc_velocities())
        assert np.array_equal(v["radius"][order], m.disc_radii())
        assert np.array_equal(v["index"], m.disc_indices())
        assert np.array_equal(v["index"] + 1, m.disc_ids())
    assert not np.array_equal(v["pos"], before)
    assert np.array_equal(m.disc_views()["pos"], v["pos"])
    # a view keeps the model alive
    ids = m.disc_indices()
    pos = m.disc_positions()
    del m
    gc.collect()
    assert np.array_equal(v["pos"][np.argsort(ids)], pos)


def test_disc_forces_after_each_call_are_those_of_the_last_step(box_file):
    a = efgdem.Model.from_scenario(box_file)
    b = efgdem.Model.from_scenario(box_file)
    a.step(7)
    for _ in range(7):
        b.step()
    assert a.disc_forces().tobytes() == b.disc_forces().tobytes()
    assert a.disc_forces().any()


def test_body_fields_and_sampling():
    m = efgdem.Model.from_scenario(EXAMPLE1)
    assert m.body_names() == ["beam"]
    m.run(0.02)
    assert m.step_count == 200 and m.time == pytest.approx(0.02)
    x, u = m.body_displacement("beam")
    assert x.shape == u.shape == (80, 2)
    assert np.array_equal(x, m.body_displacement(0)[0])
    f = m.body_fields(-1)
    assert f["stress"].shape == (80, 3) and np.array_equal(f["u"], u)
    tip = np.argmin(np.linalg.norm(x - [1.0, 0.1], axis=1))
    s = m.sample("beam", 1.0, 0.1)
    assert s["u"].shape == (2,) and s["stress"].shape == (3,)
    assert s["u"][1] == m.probe("tip_uy") and s["u"][0] == m.probe("tip_ux")
    assert np.allclose(s["u"], u[tip], rtol=1e-9, atol=0)
    assert u[:, 1].min() < -1e-4  # the disc pushes the beam down
    many = m.sample("beam", [0.5, 1.0], [0.0, 0.1])
    assert many["u"].shape == (2, 2) and np.array_equal(many["u"][1], s["u"])
    with pytest.raises(KeyError):
        m.body_fields("column")
    with pytest.raises(IndexError):
        m.body_fields(3)
    with pytest.raises(efgdem.ModelError):
        m.sample("beam", 5.0, 5.0)
    c = m.contacts()
    assert len(c) == 1 and c["kind"][0] == efgdem.CONTACT_DISC_BODY
    assert (c["other"][0], c["other_index"][0]) == (1, 0)  # body 1, body_names()[0]


def test_static_model():
    m = efgdem.Model.from_scenario(ROOT / "examples" / "timoshenko.toml")
    assert m.kind == "continuum" and m.n_discs == 0
    assert m.disc_positions().shape == (0, 2) and len(m.contacts()) == 0
    with pytest.raises(efgdem.ModelError, match="solve_static"):
        m.step()
    m.solve_static()
    assert m.probe("tip_uy") == pytest.approx(-0.0089, rel=0.02)


def test_cracked_plate_grows_and_its_fields_follow(tmp_path):
    # the example's edge crack grows 4 increments in the static solve; the
    # probes, the nodal fields and the frames are those of the grown body
    m = efgdem.Model.from_scenario(ROOT / "examples" / "cracked_plate.toml")
    n0 = m.body_fields("plate")["x"].shape[0]
    m.solve_static()
    assert m.probe("a") == pytest.approx(0.08, abs=1e-9)
    assert m.probe("K_II") == pytest.approx(0.0, abs=1e-3 * m.probe("K_I"))
    f = m.body_fields("plate")
    assert f["x"].shape[0] > n0 and np.isfinite(f["u"]).all()
    written = [p.name for p in m.write_frame(tmp_path)]
    assert "plate_cracks.vtp" in written and "plate.vtu" in written


# --- errors -----------------------------------------------------------------


def test_bad_scenario_file_raises_scenario_error_with_file_line(tmp_path):
    bad = tmp_path / "bad_box.toml"
    bad.write_text(BOX_TOML.replace("kn = 1.0e5", "kn = -1.0e5"))
    with pytest.raises(efgdem.ScenarioError) as e:
        efgdem.Model.from_scenario(bad)
    assert isinstance(e.value, ValueError)
    assert "bad_box.toml:9: material[0].kn: must be a finite number" in str(e.value)
    assert e.value.errors[0][:2] == (9, "material[0].kn")
    assert e.value.file.endswith("bad_box.toml")
    # a syntax error, and an unknown field
    bad.write_text(BOX_TOML.replace("steps = 400", "steps = = 400"))
    with pytest.raises(efgdem.ScenarioError, match=r"bad_box\.toml:3: "):
        efgdem.Model.from_scenario(bad)
    bad.write_text(BOX_TOML.replace("friction = 0.4", "friction = 0.4\nfrction = 1"))
    with pytest.raises(efgdem.ScenarioError, match=r"bad_box\.toml:\d+: .*frction"):
        efgdem.Model.from_scenario(bad)
    # a semantic error found while building: a probe of a missing disc
    bad.write_text(BOX_TOML.replace("disc = 3", "disc = 9"))
    with pytest.raises(efgdem.ScenarioError, match=r"bad_box\.toml:\d+: probe\[0\]"):
        efgdem.Model.from_scenario(bad)
    with pytest.raises(efgdem.ScenarioError, match="cannot read"):
        efgdem.Model.from_scenario(tmp_path / "missing.toml")


def test_bad_dict_raises_scenario_error_with_field():
    d = dict(BOX_DICT, simulation={"dt": -1.0, "steps": 10})
    with pytest.raises(efgdem.ScenarioError, match=r"^<dict>: simulation\.dt: must be"):
        efgdem.Model.from_dict(d)
    with pytest.raises(efgdem.ScenarioError, match=r"<dict>: granular\.discs\[1\]\[0\]: .*type `object`"):
        efgdem.Model.from_dict(dict(BOX_DICT, granular=dict(
            BOX_DICT["granular"], discs=[[0, 0, 1], [object(), 0, 1]])))


def test_dict_type_errors_name_the_field():
    import copy

    def bad(change):
        d = copy.deepcopy(BOX_DICT)
        change(d)
        with pytest.raises(efgdem.ScenarioError) as e:
            efgdem.Model.from_dict(d)
        return str(e.value)

    assert bad(lambda d: d["simulation"].update(dt="x")).startswith(
        "<dict>: simulation.dt: invalid type")
    assert bad(lambda d: d["material"][0].update(frction=1)).startswith(
        "<dict>: material[0].frction: unknown field")
    assert bad(lambda d: d["wall"][1].update(to=[1.0])).startswith("<dict>: wall[1].to: ")
    assert bad(lambda d: d["granular"].update(damping={"kind": "viscous"})).startswith(
        "<dict>: granular.damping.kind: unknown variant `viscous`")
    ex = load_toml(EXAMPLE1)
    ex["body"][0]["bc"][0]["edge"] = "lft"
    with pytest.raises(efgdem.ScenarioError, match=r"^<dict>: body\[0\]\.bc\[0\]\.edge: unknown edge `lft`"):
        efgdem.Model.from_dict(ex)


def test_model_error_is_a_runtime_error():
    assert issubclass(efgdem.ModelError, RuntimeError)
    assert issubclass(efgdem.ScenarioError, ValueError)
    # (a time step above the critical one is now refused when the scenario
    # is built: a ScenarioError; a static model cannot be stepped: a ModelError)
    d = settling(count=50)
    d["simulation"].update(dt=1e10)
    with pytest.raises(efgdem.ScenarioError, match="simulation.dt: dt = 1e10 is"):
        efgdem.Model.from_dict(d)
    m = efgdem.Model.from_scenario(ROOT / "examples" / "timoshenko.toml")
    with pytest.raises(efgdem.ModelError, match="static analysis has no time steps"):
        m.step(1)


# --- frames -------------------------------------------------------------------


def cli():
    for p in (ROOT / "target" / "release" / "efgdem", shutil.which("efgdem")):
        if p and Path(p).exists():
            return str(p)
    return None


def test_write_frame_writes_what_the_cli_writes(tmp_path):
    exe = cli()
    if exe is None:
        pytest.skip("no efgdem binary (cargo build --release)")
    sc = tmp_path / "ex1.toml"
    sc.write_text(EXAMPLE1.read_text().replace("end_time = 0.2", "end_time = 0.01"))
    subprocess.run([exe, "run", str(sc), "-o", str(tmp_path / "cli"), "-q"], check=True)
    m = efgdem.Model.from_scenario(sc)
    out = tmp_path / "py"
    first = m.write_frame(out)
    assert [p.name for p in first] == ["discs_0000000.vtp", "contacts_0000000.vtp",
                                       "beam_0000000.vtu"]
    m.step(100)
    m.write_frame(out)
    for f in ("frames/discs_0000100.vtp", "frames/contacts_0000100.vtp",
              "frames/beam_0000100.vtu", "frames/beam_0000000.vtu",
              "discs.pvd", "contacts.pvd", "beam.pvd"):
        assert (out / f).read_bytes() == (tmp_path / "cli" / f).read_bytes(), f


def test_write_frame_granular(box_file, tmp_path):
    m = efgdem.Model.from_scenario(box_file)
    m.write_frame(tmp_path)
    m.step(10)
    paths = m.write_frame(tmp_path)
    assert [p.name for p in paths] == ["discs_0000010.vtp", "contacts_0000010.vtp",
                                       "walls_0000010.vtp"]
    for d in ("discs", "contacts", "walls"):
        text = (tmp_path / f"{d}.pvd").read_text()
        assert f"frames/{d}_0000000.vtp" in text and f"frames/{d}_0000010.vtp" in text


# --- the examples ----------------------------------------------------------------


@pytest.mark.parametrize("script", ["settling_box.py", "example1_fig12.py"])
def test_examples_run(script, tmp_path):
    pytest.importorskip("matplotlib")
    png = tmp_path / "out.png"
    env = dict(os.environ, EFGDEM_FAST="1")
    r = subprocess.run([sys.executable, str(ROOT / "python" / "examples" / script), "-o", str(png)],
                       env=env, capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    assert png.stat().st_size > 10_000
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


# --- checkpoints -----------------------------------------------------------------


def test_save_and_restore_state_continue_bitwise(box_file):
    a = efgdem.Model.from_scenario(box_file)
    a.step(300)
    b = efgdem.Model.from_scenario(box_file)
    b.step(120)
    saved = b.save_state()
    c = efgdem.Model.from_scenario(box_file)
    views = c.disc_views()
    c.restore_state(saved)
    assert c.step_count == 120
    c.step(180)
    assert c.save_state() == a.save_state()
    assert np.array_equal(c.disc_positions(), a.disc_positions())
    # live views follow the restored model
    assert np.array_equal(views["pos"][np.argsort(views["index"])], a.disc_positions())


@pytest.mark.parametrize("coupling", ["exact", "compliant"])
def test_steps_in_one_call_equal_steps_one_call_each(coupling, tmp_path):
    """Within one `step(n)` or `run(until)` call an exact coupled step leaves
    its body step's end, and a compliant step within a body step its contact
    solve, to the next step (done beside the discs' step); a call of one
    step ends it before returning: the same states, bitwise."""
    text = (ROOT / "examples" / "hex_footing.toml").read_text()
    scheme = 'coupling = "exact"' if coupling == "exact" else 'coupling = "compliant"\nsubsteps = 4'
    footing = tmp_path / "footing.toml"
    footing.write_text(text.replace("[simulation]\n", f"[simulation]\n{scheme}\n", 1))
    footing = str(footing)
    a = efgdem.Model.from_scenario(footing)
    a.step(1500)
    b = efgdem.Model.from_scenario(footing)
    for _ in range(1500):
        b.step(1)
    c = efgdem.Model.from_scenario(footing)
    c.run(1500 * c.dt)
    assert len(a.contacts()) > 10
    assert a.save_state() == b.save_state() == c.save_state()


def test_a_state_of_another_model_is_refused(box_file, tmp_path):
    m = efgdem.Model.from_scenario(box_file)
    other = efgdem.Model.from_scenario(EXAMPLE1)
    with pytest.raises(efgdem.ModelError):
        m.restore_state(other.save_state())
    with pytest.raises(efgdem.ModelError):
        m.restore_state(b"not a state")


# --- conventions and settle-then-place ----------------------------------------


def deposit_with_footing(remove, rect=((10.0, 20.0), (30.0, 30.0))):
    """`settling()` deposited before the run, with a footing in its bed."""
    d = settling()
    d["granular"]["discs"].update({"method": "deposit", "settle_steps": 4000})
    d["body"] = [{
        "name": "footing", "rectangle": [list(rect[0]), list(rect[1])], "nodes": [5, 3],
        "elastic": {"E": 1.0e8, "nu": 0.2, "density": 1.0},
        "self_weight": False, "bc": [{"edge": "top", "fixed": True}],
    }]
    if remove:
        d["body"][0]["overlapping_discs"] = "remove"
    return d


def test_a_footing_in_a_future_bed_is_refused_and_placed_after_with_remove():
    with pytest.raises(efgdem.ScenarioError, match="lies where discs will be") as e:
        efgdem.Model.from_dict(deposit_with_footing(False, ((10.0, 2.0), (30.0, 10.0))))
    assert e.value.errors[0][1] == "body[0].rectangle"
    m = efgdem.Model.from_dict(deposit_with_footing(True))
    # the settled bed without the footing: count the discs the footing
    # overlaps by more than 1e-3 of their radius, independently
    bed = deposit_with_footing(True)
    del bed["body"]
    b = efgdem.Model.from_dict(bed)
    p, r = b.disc_positions(), b.disc_radii()
    nearest = np.clip(p, [10.0, 20.0], [30.0, 30.0])
    inside = (nearest == p).all(axis=1)
    hit = inside | (np.linalg.norm(p - nearest, axis=1) < r * (1 - 1e-3))
    assert 0 < hit.sum() < 300
    assert m.n_discs == 300 - hit.sum()
    # the others keep their order, numbered from 1
    assert np.array_equal(m.disc_positions(), p[~hit])


def test_rectangle_forms_and_centre_spellings_build_the_same_model():
    d = settling()
    a = efgdem.Model.from_dict(d)
    d["granular"]["discs"]["box"] = {"origin": [0, 0], "size": [40, 60]}
    assert np.array_equal(efgdem.Model.from_dict(d).disc_positions(), a.disc_positions())
    plate = {
        "simulation": {"analysis": "static"},
        "body": [{"name": "p", "outline": [[0, 0], [4, 0], [4, 2], [0, 2]], "spacing": 0.25,
                  "holes": [{"centre": [2.0, 1.0], "radius": 0.5}],
                  "elastic": {"E": 1000.0, "nu": 0.3},
                  "bc": [{"edge": "outline", "fixed": True}]}],
    }
    x = efgdem.Model.from_dict(plate).body_fields(0)["x"]
    plate["body"][0]["holes"] = [{"center": [2.0, 1.0], "radius": 0.5}]
    assert np.array_equal(efgdem.Model.from_dict(plate).body_fields(0)["x"], x)


# --- guards in the model ------------------------------------------------------

# A soft EFG footing (E = 2 GPa) pushed into a hexagonal bed of 446 discs,
# with the predicted sub-cycled scheme named at 10 substeps against the
# build's warning: the scheme creates energy and the model's guard stops it.
SOFT_FOOTING = (
    (ROOT / "examples" / "hex_footing.toml")
    .read_text()
    .replace("end_time = 0.05\n", 'end_time = 0.08\nsubsteps = 10\ncoupling = "predicted"\n')
)


def test_a_subcycled_body_past_its_limit_raises_model_error(tmp_path):
    path = tmp_path / "soft.toml"
    path.write_text(SOFT_FOOTING)
    m = efgdem.Model.from_scenario(str(path))
    with pytest.raises(efgdem.ModelError, match=r"body `footing`: the sub-cycled scheme \(predicted\) created"):
        m.run(0.08)
    # stopped before the end, at the step that failed
    assert 0.015 < m.time < 0.075


# --- parallel bonds ----------------------------------------------------------

# A bonded hexagonal block (209 discs, 565 touching pairs) crushed between
# two platens: bonds break from about step 1 200 on.
BONDED = ROOT / "tests" / "common" / "bonded_block.toml"


def test_bonds_and_their_breakage_events():
    import tomllib

    runs = []
    for threads in (1, 2):
        m = efgdem.Model.from_dict(tomllib.loads(BONDED.read_text()), threads=threads)
        m.step()  # the bonds are made at the start of step 1
        b = m.bonds()
        assert len(b["a"]) == 565 and b["a"].dtype == np.uint32
        assert (b["a"] < b["b"]).all() and (b["radius"] == 0.0025).all()
        # numbers from 1 as in the files, indices from 0
        assert (b["a"] == b["a_index"] + 1).all() and (b["b"] == b["b_index"] + 1).all()
        m.step(4999)
        b, k = m.bonds(), m.bond_breaks()
        assert len(b["a"]) + len(k["a"]) == 565 and len(k["a"]) > 50
        assert set(np.unique(k["mode"])) <= {0, 1} and k["mode"].dtype == np.uint8
        assert (np.diff(k["step"].astype(np.int64)) >= 0).all() and k["step"][-1] <= 5000
        assert (k["energy"] > 0).all() and np.allclose(np.hypot(k["nx"], k["ny"]), 1.0)
        # no pair is both intact and broken
        intact = set(zip(b["a"].tolist(), b["b"].tolist()))
        assert not intact & set(zip(k["a"].tolist(), k["b"].tolist()))
        runs.append((b, k))
    for name in runs[0][1]:
        assert runs[0][1][name].tobytes() == runs[1][1][name].tobytes(), name
    for name in runs[0][0]:
        assert runs[0][0][name].tobytes() == runs[1][0][name].tobytes(), name


CLUMP_PILE = ROOT / "tests" / "common" / "clump_pile.toml"


def test_clumps_view():
    import tomllib

    m = efgdem.Model.from_dict(tomllib.loads(CLUMP_PILE.read_text()), threads=2)
    c, per_disc = m.clumps(), m.disc_clumps()
    n = len(c["x"])
    assert n > 30 and len(c["first"]) == n + 1 and c["first"][-1] == len(c["members"])
    assert (c["members"] == c["members_index"] + 1).all()
    # each disc's clump number names the clump that lists it (0: none)
    assert len(per_disc) == m.n_discs and per_disc.dtype == np.int64
    for k in range(n):
        for d in c["members_index"][c["first"][k] : c["first"][k + 1]]:
            assert per_disc[d] == k + 1
    assert (per_disc == 0).sum() == m.n_discs - len(c["members"])
    # a clump's mass is that of the union of its discs: less than their sum
    r = m.disc_radii()
    for k in range(n):
        rs = r[c["members_index"][c["first"][k] : c["first"][k + 1]]]
        assert c["mass"][k] < 2650.0 * np.pi * (rs**2).sum()
    m.step(500)
    c = m.clumps()
    assert (c["vy"] < 0).any() and np.isfinite(c["theta"]).all()
    # members move with their clump: all of a clump's discs share its spin
    spins = m.disc_spins()
    for k in range(n):
        members = c["members_index"][c["first"][k] : c["first"][k + 1]]
        assert (spins[members] == c["omega"][k]).all()
