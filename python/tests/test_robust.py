"""The Python module never crashes the interpreter and never answers a
misuse with None: recursive or cyclic dicts raise ScenarioError, run(inf)
raises, Ctrl-C interrupts a long run within a second, a model used in a
forked child works, damaged saved states are refused, absurd thread counts
are lowered, devices are not read as scenarios; the fuzzing that found
these is kept as a property test."""

import multiprocessing
import os
import random
import signal
import sys
import threading
import time
import warnings

import pytest

import efgdem

# A small settling box (a few ms per step at most).
SETTLING = {
    "simulation": {"steps": 100000, "gravity": [0.0, -9.81]},
    "material": [
        {"name": "sand", "density": 2650.0, "kn": 1.0e6, "ks": 5.0e5, "friction": 0.5}
    ],
    "granular": {
        "material": "sand",
        "discs": {
            "generate": "hex",
            "box": [[0.0, 0.0], [0.1, 0.08]],
            "radius": [0.0035, 0.0045],
            "jitter": 0.5,
            "seed": 3,
        },
        "damping": {"kind": "critical-ratio", "zeta": 0.2},
    },
    "wall": [
        {"name": "floor", "from": [0.0, 0.0], "to": [0.1, 0.0]},
        {"name": "left", "from": [0.0, 0.0], "to": [0.0, 0.3]},
        {"name": "right", "from": [0.1, 0.0], "to": [0.1, 0.3]},
    ],
}

# A static cantilever: a continuum model.
CANTILEVER = {
    "simulation": {"analysis": "static"},
    "body": [
        {
            "name": "beam",
            "rectangle": {"origin": [0.0, -0.5], "size": [4.0, 1.0]},
            "nodes": [9, 3],
            "elastic": {"E": 1.0e7, "nu": 0.3},
            "bc": [{"edge": "left", "fixed": True}],
        }
    ],
}


def test_a_dict_that_contains_itself_raises():
    d = {"simulation": {}}
    d["self"] = d
    with pytest.raises(efgdem.ScenarioError, match="contains itself"):
        efgdem.Model.from_dict(d)
    with pytest.raises(efgdem.ScenarioError, match="contains itself"):
        efgdem.scenario_toml(d)
    lst = []
    lst.append(lst)
    with pytest.raises(efgdem.ScenarioError, match="contains itself"):
        efgdem.Model.from_dict({"granular": {"discs": lst}})
    # the same dict twice is a tree, not a cycle
    mat = dict(SETTLING["material"][0])
    d = dict(SETTLING, material=[mat])
    d["wall"] = [dict(w, material="sand") for w in SETTLING["wall"]]
    efgdem.scenario_toml(d)


def test_a_dict_nested_30000_deep_raises():
    deep = {}
    cur = deep
    for _ in range(30000):
        cur["a"] = {}
        cur = cur["a"]
    with pytest.raises(efgdem.ScenarioError, match="nested more than 32 levels"):
        efgdem.Model.from_dict(deep)
    lst = cur = []
    for _ in range(30000):
        cur.append([])
        cur = cur[0]
    with pytest.raises(efgdem.ScenarioError, match="nested more than"):
        efgdem.scenario_toml({"granular": {"discs": lst}})


def test_a_table_given_as_an_array_is_refused():
    d = dict(CANTILEVER)
    d["body"] = [dict(CANTILEVER["body"][0], rectangle=[[0.1, 0.1], [0.3, 0.2]])]
    with pytest.raises(efgdem.ScenarioError) as e:
        efgdem.Model.from_dict(d)
    assert "body[0].rectangle: invalid type: sequence, expected a table" in str(e.value)


def test_run_to_a_non_finite_time_raises():
    m = efgdem.Model.from_dict(SETTLING)
    for t in (float("inf"), float("nan"), -float("inf")):
        with pytest.raises(ValueError, match="must be a finite number"):
            m.run(t)
    assert m.step_count == 0


def interrupt_after(seconds):
    """SIGINT to this process after `seconds` (as Ctrl-C); the time sent."""
    sent = {}

    def fire():
        sent["t"] = time.monotonic()
        os.kill(os.getpid(), signal.SIGINT)

    t = threading.Timer(seconds, fire)
    t.start()
    return t, sent


@pytest.mark.parametrize("call", ["run", "step"])
def test_ctrl_c_interrupts_a_long_call_within_a_second(call):
    m = efgdem.Model.from_dict(SETTLING)
    timer, sent = interrupt_after(0.5)
    with pytest.raises(KeyboardInterrupt):
        if call == "run":
            m.run(1.0e12)
        else:
            m.step(10**12)
    late = time.monotonic() - sent["t"]
    timer.join()
    assert late < 1.0, f"KeyboardInterrupt {late:.2f} s after the signal"
    # the model is between two steps and steps on
    n = m.step_count
    assert n > 0
    m.step(3)
    assert m.step_count == n + 3


def child_steps(model, queue):
    model.step(20)
    queue.put((model.step_count, model.disc_positions().sum()))


@pytest.mark.skipif(sys.platform == "win32", reason="fork")
def test_a_model_used_in_a_forked_child_works():
    m = efgdem.Model.from_dict(SETTLING, threads=2)
    m.step(5)  # the parent's pool has run
    ctx = multiprocessing.get_context("fork")
    q = ctx.Queue()
    p = ctx.Process(target=child_steps, args=(m, q))
    p.start()
    p.join(60)
    assert p.exitcode == 0, "the child did not finish"
    steps, total = q.get(timeout=5)
    # the same as the parent stepping on
    m.step(20)
    assert steps == m.step_count == 25
    assert total == m.disc_positions().sum()


def test_misuse_raises_and_never_returns_none():
    g = efgdem.Model.from_dict(SETTLING)
    with pytest.raises(efgdem.ModelError, match="no static solve"):
        g.solve_static()
    c = efgdem.Model.from_dict(CANTILEVER)
    with pytest.raises(efgdem.ModelError, match="no time steps"):
        c.step()
    with pytest.raises(IndexError):
        g.body_fields(0)
    with pytest.raises(KeyError):
        g.probe("nope")
    with pytest.raises(OverflowError):
        g.step(-1)
    with pytest.raises(TypeError):
        g.run("1.0")
    with pytest.raises(efgdem.ModelError):
        g.restore_state(b"")
    with pytest.raises(efgdem.ModelError):
        g.restore_state(c.save_state())
    assert c.solve_static() is None  # the one call that returns nothing
    with pytest.raises(efgdem.ScenarioError, match="a device, not a file"):
        efgdem.Model.from_scenario("/dev/zero")
    with pytest.raises(efgdem.ScenarioError):
        efgdem.Model.from_dict({"simulation": {"steps": 2**70}})


def test_every_single_bit_flip_of_a_saved_state_is_refused():
    m = efgdem.Model.from_dict(SETTLING)
    m.step(10)
    good = m.save_state()
    before = m.save_state()
    rng = random.Random(26)
    for _ in range(300):
        bit = rng.randrange(8 * len(good))
        bad = bytearray(good)
        bad[bit // 8] ^= 1 << (bit % 8)
        with pytest.raises(efgdem.ModelError):
            m.restore_state(bytes(bad))
    assert m.save_state() == before
    m.restore_state(good)


def test_an_absurd_thread_count_is_lowered_with_a_warning():
    t0 = time.monotonic()
    with warnings.catch_warnings(record=True) as w:
        warnings.simplefilter("always")
        m = efgdem.Model.from_dict(SETTLING, threads=10**12)
    assert time.monotonic() - t0 < 30
    assert any("threads asked for" in str(x.message) for x in w)
    m.step(2)


def random_value(rng, depth):
    """A value of any type, nested up to `depth` (or beyond, sometimes)."""
    k = rng.randrange(10)
    if k == 0:
        return rng.choice([2**63, -(2**63) - 1, 10**30, 2**64])
    if k == 1:
        return rng.choice([float("nan"), float("inf"), -1e308, 5e-324, 0.0])
    if k == 2:
        return rng.choice(["", "zzz", "/dev/zero", "hex", "static", None])
    if k == 3 and depth > 0:
        return [random_value(rng, depth - 1) for _ in range(rng.randrange(4))]
    if k == 4 and depth > 0:
        return {rng.choice(["a", "b", "discs", "box"]): random_value(rng, depth - 1)}
    return rng.choice([True, 1, 2, 3, -1, 1e-3])


def mutate(rng, d, depth=0):
    """A copy of `d` with a random value replaced, a cycle or a deep chain."""
    out = {k: v for k, v in d.items()}
    keys = list(out)
    k = rng.choice(keys)
    r = rng.randrange(10)
    if r == 0:
        out[k] = out  # a cycle
    elif r == 1:
        chain = cur = {}
        for _ in range(rng.choice([40, 3000])):
            cur["x"] = {}
            cur = cur["x"]
        out[k] = chain
    elif isinstance(out[k], dict) and depth < 4 and r < 6:
        out[k] = mutate(rng, out[k], depth + 1)
    elif isinstance(out[k], list) and out[k] and isinstance(out[k][0], dict) and r < 6:
        out[k] = [mutate(rng, out[k][0], depth + 1)] + out[k][1:]
    else:
        out[k] = random_value(rng, 3)
    return out


def test_fuzzed_dicts_raise_or_build_and_never_crash():
    n = int(os.environ.get("EFGDEM_PY_FUZZ_N", "300"))
    rng = random.Random(int(os.environ.get("EFGDEM_PY_FUZZ_SEED", "26")))
    outcomes = {"built": 0, "refused": 0}
    for _ in range(n):
        d = mutate(rng, rng.choice([SETTLING, CANTILEVER]))
        try:
            m = efgdem.Model.from_dict(d)
        except efgdem.ScenarioError:
            outcomes["refused"] += 1
            continue
        outcomes["built"] += 1
        try:
            m.step(2) if m.kind != "continuum" else m.solve_static()
        except efgdem.ModelError:
            pass
    assert outcomes["refused"] > n // 4, outcomes
