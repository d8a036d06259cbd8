//! Checkpoint/restart of the library (issue 12): a run of N steps and a run
//! of k steps, saved to bytes, restored onto a model built afresh from the
//! same scenario and stepped N − k more, end bitwise equal — granular,
//! continuum (EFG, FE) and coupled models, on 1 and 2 threads. A state that
//! does not fit the model is refused, and the model left as it was.

use efgdem::coupling::energy::WorkMeter;
use efgdem::model::{Model, ModelState, STATE_FORMAT_VERSION, SystemState};
use efgdem::scenario;

fn build(src: &str) -> Model {
    scenario::parse(src, "<state_restart>")
        .unwrap()
        .build()
        .unwrap()
}

fn run(m: &mut Model, n: usize) {
    for _ in 0..n {
        m.step().unwrap();
    }
}

/// A: `n` steps. B: `k` steps, saved as bytes. C: built afresh, restored
/// from those bytes, `n − k` steps. Returns A, C and the bytes.
fn restart(src: &str, n: usize, k: usize) -> (Model, Model, Vec<u8>) {
    let mut a = build(src);
    run(&mut a, n);
    let mut b = build(src);
    run(&mut b, k);
    let saved = b.save_state();
    let bytes = saved.to_bytes();
    drop(b);
    let mut c = build(src);
    let s = ModelState::from_bytes(&bytes).unwrap();
    assert!(s == saved, "the bytes give back the state");
    c.restore_state(&s).unwrap();
    assert!(
        c.save_state().to_bytes() == bytes,
        "the restored model saves the state it was given"
    );
    run(&mut c, n - k);
    (a, c, bytes)
}

fn bits(v: impl IntoIterator<Item = f64>) -> Vec<u64> {
    v.into_iter().map(f64::to_bits).collect()
}

/// Every saved array of `a` and `c` bitwise equal, and what the outputs
/// read (discs in id order, contacts, body fields, energies).
fn assert_same(a: &Model, c: &Model) {
    assert_eq!(a.step, c.step);
    assert_eq!(a.time().to_bits(), c.time().to_bits());
    assert!(
        a.save_state().to_bytes() == c.save_state().to_bytes(),
        "the states differ"
    );
    if let (Some(ga), Some(gc)) = (a.granular(), c.granular()) {
        let by_id = |g: &efgdem::dem::Granular| {
            let p = &g.particles;
            let s = |id: usize| g.slot(id);
            (
                bits((0..p.len()).flat_map(|i| [p.pos[s(i)].x, p.pos[s(i)].y])),
                bits((0..p.len()).flat_map(|i| [p.vel[s(i)].x, p.vel[s(i)].y])),
                bits((0..p.len()).flat_map(|i| [p.omega[s(i)], p.theta[s(i)]])),
            )
        };
        assert_eq!(by_id(ga), by_id(gc));
        assert_eq!(ga.particles.id, gc.particles.id);
        let (ea, ec) = (ga.energies(), gc.energies());
        assert_eq!(
            bits([ea.kinetic, ea.rotational, ea.spring, ea.gravity]),
            bits([ec.kinetic, ec.rotational, ec.spring, ec.gravity])
        );
        assert_eq!(ga.grid.rebuilds, gc.grid.rebuilds);
    }
    assert_eq!(a.contacts(), c.contacts());
    for i in 0..a.n_bodies() {
        let u = |m: &Model| match m.body(i) {
            efgdem::model::body::BodyRef::Efg(b) => {
                bits(b.state.u.iter().chain(&b.state.v).copied())
            }
            efgdem::model::body::BodyRef::Fem(b) => {
                bits(b.state.u.iter().chain(&b.state.v).copied())
            }
        };
        assert_eq!(u(a), u(c));
        assert_eq!(
            a.body(i).strain_energy().to_bits(),
            c.body(i).strain_energy().to_bits()
        );
    }
}

/// ~1000 discs settling in a box with friction, rolling resistance, contact
/// dashpots and a wall pushing in; with `servo`, the right wall follows a
/// strain rate instead and a servo wall presses the bed from above (its
/// right end joined to the right wall: it shrinks as that one moves in).
fn packing(rolling: f64, servo: bool) -> String {
    let (right, top) = if servo {
        (
            "strain_rate = 0.07",
            r#"
[[wall]]
name = "top"
from = [0.0, 0.243]
to = [0.3, 0.243]
servo = { stress = 2000.0, max_velocity = 0.6 }
"#,
        )
    } else {
        ("velocity = [-0.02, 0.0]", "")
    };
    format!(
        r#"
[simulation]
steps = 2000
dt = 6.4e-5
gravity = [0.0, -9.81]

[[material]]
name = "sand"
density = 2650.0
kn = 1.0e6
ks = 5.0e5
friction = 0.5
rolling_friction = {rolling}

[granular]
material = "sand"
discs = {{ generate = "hex", box = [[0.0, 0.0], [0.3, 0.24]], radius = [0.0035, 0.0045], jitter = 0.5, seed = 3 }}
damping = {{ kind = "critical-ratio", zeta = 0.2 }}

[[wall]]
name = "floor"
from = [0.0, 0.0]
to = [0.3, 0.0]

[[wall]]
name = "left"
from = [0.0, 0.0]
to = [0.0, 0.4]

[[wall]]
name = "right"
from = [0.3, 0.0]
to = [0.3, 0.4]
{right}
{top}"#
    )
}

/// The DEM state at the save point is a loaded packing, and the restored
/// model rebuilds its neighbour list (and renumbers) before the end.
fn check_packing(rolling: f64, servo: bool) {
    let src = packing(rolling, servo);
    let (n, k) = (2000, 1300);
    let (a, c, bytes) = restart(&src, n, k);
    let s = ModelState::from_bytes(&bytes).unwrap();
    let SystemState::Granular(g) = &s.system else {
        panic!("a granular state")
    };
    let discs = g.id.len();
    eprintln!(
        "packing (rolling {rolling}) at the save: {} shear springs loaded of {} pairs, {} wall springs of {}",
        g.shear.iter().filter(|f| **f != 0.0).count(),
        g.pairs.len(),
        g.wall_pairs.iter().filter(|w| w.fs != 0.0).count(),
        g.wall_pairs.len()
    );
    assert!(discs > 900, "{discs} discs");
    let loaded = g.shear.iter().filter(|f| **f != 0.0).count();
    let on_walls = g.wall_pairs.iter().filter(|w| w.fs != 0.0).count();
    assert!(loaded > discs, "{loaded} disc–disc shear springs loaded");
    assert!(on_walls > 10, "{on_walls} disc–wall shear springs loaded");
    if rolling > 0.0 {
        assert!(g.roll.iter().filter(|m| **m != 0.0).count() > discs);
    } else {
        assert!(g.roll.is_empty());
    }
    let rebuilds = c.granular().unwrap().grid.rebuilds;
    assert!(
        rebuilds > g.rebuilds + 1,
        "rebuilds after the restore: {} → {rebuilds}",
        g.rebuilds
    );
    let (dd, dw) = c.granular().unwrap().touching();
    assert!(
        dd > discs / 2 && dw > 10,
        "{dd} disc and {dw} wall contacts"
    );
    eprintln!(
        "packing (rolling {rolling}): {discs} discs, {} pairs, {} wall pairs, checkpoint {} bytes ({:.0} B/disc); rebuilds {} at the save, {rebuilds} at the end",
        g.pairs.len(),
        g.wall_pairs.len(),
        bytes.len(),
        bytes.len() as f64 / discs as f64,
        g.rebuilds
    );
    if servo {
        // the servo wall came down onto the bed before the save and holds
        // it; its joined end followed the right wall in
        let top = &g.walls[3];
        let w = c
            .granular()
            .unwrap()
            .walls
            .iter()
            .find(|w| w.name == "top")
            .unwrap();
        eprintln!(
            "servo wall at the save: y = {:.5}, length {:.5}, v = {:?}; at the end {} discs under it, σ = {:.1}",
            top.a.y,
            (top.b - top.a).norm(),
            top.vel,
            w.contacts,
            w.normal_stress(1.0)
        );
        assert!(top.a.y < 0.24 && (top.b - top.a).norm() < 0.299);
        assert!(w.contacts > 10 && top.vel.y != 0.0);
    }
    assert_same(&a, &c);
}

#[test]
fn granular_packing_restarts_bitwise() {
    check_packing(0.0, false);
}

/// With rolling resistance, a servo wall and a strain-rate wall.
#[test]
fn granular_packing_with_rolling_resistance_restarts_bitwise() {
    check_packing(0.1, true);
}

/// A small biaxial test (issue 13 §5): four servo walls (top and bottom
/// with integral action) consolidate a grown packing; from step 600 the
/// top and bottom walls follow a strain rate (wall `phases`) while the
/// side servos hold, now with integral action.
fn biaxial() -> String {
    let servo = "servo = { stress = 1.0e5, max_velocity = 0.1, relaxation = 1.0, integral = 0.1 }";
    let axial = format!("phases = [{{ until_step = 600, {servo} }}, {{ strain_rate = 2.0 }}]");
    let lateral = format!(
        "phases = [{{ until_step = 600, servo = {{ stress = 1.0e5, max_velocity = 0.1 }} }}, {{ {servo} }}]"
    );
    let wall = |name: &str, from: &str, to: &str, motion: &str| {
        format!(
            "[[wall]]\nname = \"{name}\"\nfrom = {from}\nto = {to}\nmaterial = \"smooth\"\n{motion}\n\n"
        )
    };
    format!(
        r#"[simulation]
dt = 1.4e-6
steps = 1500

[[material]]
name = "grain"
density = 2650.0
kn = 1.0e8
ks = 5.0e7
friction = 0.5
rolling_friction = 0.1

[[material]]
name = "smooth"
kn = 1.0e8

[granular]
material = "grain"
discs = {{ generate = "random", method = "grow", box = [[0.0, 0.0], [0.012, 0.024]], radius = [0.0005, 0.001], count = 120, seed = 4, settle_steps = 3000, settle_material = "smooth" }}
damping = {{ kind = "critical-ratio", zeta = 0.2 }}

{}{}{}{}"#,
        wall("bottom", "[0.0, 0.0]", "[0.012, 0.0]", &axial),
        wall("top", "[0.0, 0.024]", "[0.012, 0.024]", &axial),
        wall("left", "[0.0, 0.0]", "[0.0, 0.024]", &lateral),
        wall("right", "[0.012, 0.0]", "[0.012, 0.024]", &lateral),
    )
}

/// Saved during the consolidation and during the shearing (servos'
/// integral velocities in the state), restored, continued across the
/// change of phases: bitwise the run in one go.
#[test]
fn biaxial_test_with_wall_phases_restarts_bitwise() {
    let src = biaxial();
    for k in [400, 900] {
        let (a, c, bytes) = restart(&src, 1500, k);
        assert_same(&a, &c);
        let s = ModelState::from_bytes(&bytes).unwrap();
        let SystemState::Granular(g) = &s.system else {
            panic!("a granular state")
        };
        // the servos' integral velocities are part of the state
        let moving = g.walls.iter().filter(|w| w.integral != 0.0).count();
        // (consolidation: top and bottom with integral action, the
        // sides without; shearing: the sides with it)
        assert_eq!(moving, 2, "at step {k}");
        let w = &a.granular().unwrap().walls;
        eprintln!(
            "saved at {k}: {} bytes; at the end the top wall at y = {:.6}, sides at x = {:.6}, {:.6}",
            bytes.len(),
            w[1].a.y,
            w[2].a.x,
            w[3].a.x
        );
    }
}

/// A cantilever (EFG or FE) under self-weight whose right edge is driven
/// down for part of the run (penalty refinement, work of moving edges, FE
/// support reactions).
fn cantilever(method: &str) -> String {
    format!(
        r#"
[simulation]
analysis = "dynamic"
dt = 2.0e-3
steps = 240
gravity = [0.0, -9.81]

[[body]]
name = "beam"
method = "{method}"
rectangle = {{ origin = [0.0, -0.2], size = [4.0, 0.4] }}
nodes = [21, 5]
elastic = {{ E = 1.0e6, nu = 0.3, density = 10.0, plane = "stress" }}
newmark = {{ gamma = 0.5, beta = 0.25 }}

[[body.bc]]
edge = "left"
fixed = true

[[body.bc]]
edge = "right"
uy = {{ velocity = -0.05, until_step = 150 }}
"#
    )
}

#[test]
fn efg_body_restarts_bitwise() {
    let (a, c, bytes) = restart(&cantilever("efg"), 240, 97);
    eprintln!("EFG cantilever: checkpoint {} bytes", bytes.len());
    assert_same(&a, &c);
    assert!(a.body(0).kinetic_energy() > 0.0);
}

#[test]
fn fem_body_restarts_bitwise() {
    let (a, c, bytes) = restart(&cantilever("fem-q4"), 240, 97);
    eprintln!("FE cantilever: checkpoint {} bytes", bytes.len());
    assert_same(&a, &c);
    let SystemState::Continuum(b) = ModelState::from_bytes(&bytes).unwrap().system else {
        panic!("a continuum state")
    };
    assert!(
        b[0].reactions.iter().any(|r| *r != 0.0),
        "support reactions saved"
    );
    assert!(b[0].motion_work != 0.0);
}

/// Example 1 (a disc on the free end of an EFG cantilever), shortened.
const DISC_ON_BEAM: &str = r#"
[simulation]
dt = 1.0e-4
steps = 700
gravity = [0.0, -9.81]

[[material]]
name = "disc"
density = 1000.0
kn = 1.0e6
ks = 1.0e6
friction = 0.5

[granular]
material = "disc"
thickness = 1.0
discs = [[0.999999, 0.15, 0.05]]
damping = { kind = "none" }

[[body]]
name = "beam"
rectangle = { origin = [0.0, -0.1], size = [1.0, 0.2] }
nodes = [20, 4]
gauss = 4
d_max = 2.0
elastic = { E = 2.1e8, nu = 0.3, density = 2000.0, thickness = 0.025, plane = "stress" }
newmark = { gamma = 1.5, beta = 0.8 }
self_weight = false
contact_edges = ["top", "right"]

[[body.bc]]
edge = "left"
fixed = true
"#;

#[test]
fn disc_on_efg_beam_restarts_bitwise() {
    let (a, c, bytes) = restart(DISC_ON_BEAM, 700, 400);
    let s = ModelState::from_bytes(&bytes).unwrap();
    let SystemState::Coupled(m) = &s.system else {
        panic!("a coupled state")
    };
    assert_eq!(m.contacts.len(), 1, "the disc is on the beam at the save");
    let green = m.bodies[0].boundary.as_ref().unwrap().green.as_ref();
    assert!(green.is_some_and(|g| !g.is_empty()), "Green matrix built");
    eprintln!("disc on beam: checkpoint {} bytes", bytes.len());
    assert_same(&a, &c);
}

/// The driver's energy account ([`WorkMeter`]) lives beside the model: a
/// restart saves it too, and the account after the restart is bitwise the
/// one of the run in one go.
#[test]
fn energy_account_restarts_with_the_model() {
    let (n, k) = (700, 400);
    let go = |m: &mut Model, w: &mut WorkMeter, steps: usize| {
        for _ in 0..steps {
            m.step().unwrap();
            w.after_step(m.granular().unwrap());
        }
    };
    let account = |m: &Model, w: &WorkMeter| {
        let e = w.account(m.coupled().unwrap());
        bits([e.kin_dem, e.kin_body, e.strain, e.contact, e.w_ext, e.diss])
    };
    let mut a = build(DISC_ON_BEAM);
    let mut wa = WorkMeter::new(a.coupled().unwrap());
    go(&mut a, &mut wa, n);
    let mut b = build(DISC_ON_BEAM);
    let mut wb = WorkMeter::new(b.coupled().unwrap());
    go(&mut b, &mut wb, k);
    let (model_bytes, meter_bytes) = (b.save_state().to_bytes(), postcard::to_stdvec(&wb).unwrap());
    let mut c = build(DISC_ON_BEAM);
    c.restore_state(&ModelState::from_bytes(&model_bytes).unwrap())
        .unwrap();
    let mut wc: WorkMeter = postcard::from_bytes(&meter_bytes).unwrap();
    assert_eq!(account(&b, &wb), account(&c, &wc));
    go(&mut c, &mut wc, n - k);
    assert_eq!(account(&a, &wa), account(&c, &wc));
}

/// A bed of discs between walls on an EFG plate (fixed at its bottom),
/// settling with many disc–body, disc–disc and disc–wall contacts.
fn bed_on_plate(method: &str, extra: &str) -> String {
    format!(
        r#"
[simulation]
dt = 5.0e-5
steps = 800
gravity = [0.0, -9.81]
{extra}

[[material]]
name = "sand"
density = 2650.0
kn = 1.0e6
ks = 5.0e5
friction = 0.5
rolling_friction = 0.05

[granular]
material = "sand"
discs = {{ generate = "hex", box = [[0.0, 0.0], [0.2, 0.04]], radius = [0.0045, 0.005], jitter = 0.2, seed = 5 }}
damping = {{ kind = "critical-ratio", zeta = 0.1 }}

[[wall]]
name = "left"
from = [0.0, -0.05]
to = [0.0, 0.1]

[[wall]]
name = "right"
from = [0.2, -0.05]
to = [0.2, 0.1]

[[body]]
name = "plate"
method = "{method}"
rectangle = {{ origin = [0.0, -0.04], size = [0.2, 0.04] }}
nodes = [21, 5]
elastic = {{ E = 5.0e7, nu = 0.3, density = 2000.0, plane = "strain" }}
contact_edges = ["top"]

[[body.bc]]
edge = "bottom"
fixed = true
"#
    )
}

fn check_bed(src: &str, n: usize, k: usize) -> (Model, Model) {
    let (a, c, bytes) = restart(src, n, k);
    let s = ModelState::from_bytes(&bytes).unwrap();
    let SystemState::Coupled(m) = &s.system else {
        panic!("a coupled state")
    };
    let on_body = m.contacts.iter().filter(|q| q.fs != 0.0).count();
    eprintln!(
        "bed at the save: {on_body} of {} disc–body contacts with shear",
        m.contacts.len()
    );
    assert!(on_body >= 10, "{on_body} disc–body contacts with shear");
    assert!(m.granular.shear.iter().filter(|f| **f != 0.0).count() > 20);
    let green = m.bodies[0].boundary.as_ref().unwrap().green.as_ref();
    eprintln!(
        "bed on plate: {} discs, {} disc–body contacts, Green matrix in {} batch(es), checkpoint {} bytes",
        m.granular.id.len(),
        m.contacts.len(),
        green.map_or(0, Vec::len),
        bytes.len()
    );
    assert_same(&a, &c);
    (a, c)
}

#[test]
fn bed_on_efg_plate_restarts_bitwise() {
    check_bed(&bed_on_plate("efg", ""), 800, 450);
}

/// Sub-cycled (an FE plate): saved in the middle of a body step, with the
/// boundary on its path and the discs' loads of its first DEM steps
/// pending.
#[test]
fn bed_on_fem_plate_substepped_restarts_bitwise() {
    let src = bed_on_plate("fem-q4", "substeps = 3");
    // a plate ten times stiffer: the predicted scheme is safe for it (the
    // softer one gets the compliant scheme)
    let src = src
        .replace(
            "contact_edges",
            "newmark = { gamma = 1.5, beta = 0.8 }\ncontact_edges",
        )
        .replace("E = 5.0e7", "E = 5.0e8");
    let (n, k) = (800, 449);
    let mut b = build(&src);
    run(&mut b, k);
    let s = b.save_state();
    let SystemState::Coupled(m) = &s.system else {
        panic!("a coupled state")
    };
    assert_eq!(m.sub, k % 3);
    let path = &m.bodies[0].boundary.as_ref().expect("a boundary").path;
    assert!(!path.end.is_empty(), "a path under way");
    assert!(
        path.acc.iter().flatten().any(|f| f.x != 0.0 || f.y != 0.0),
        "loads pending"
    );
    check_bed(&src, n, k);
}

/// The automatic scheme (`coupling = "auto"`) given `substeps = 4` on the
/// soft plate picks the compliant sub-cycled scheme; saved in the middle
/// of a body step (its boundary's response pending), restored, bitwise
/// equal — and equal on 1 and 2 threads ([`restarts_across_thread_counts`]).
#[test]
fn bed_on_compliant_plate_restarts_bitwise() {
    let src = bed_on_plate("efg", "substeps = 4");
    let m = build(&src);
    let choice = m.coupled().unwrap().choice.clone().unwrap();
    assert_eq!(choice.scheme.name(), "compliant", "{}", choice.why);
    let (a, c, bytes) = restart(&src, 800, 450);
    let s = ModelState::from_bytes(&bytes).unwrap();
    let SystemState::Coupled(m) = &s.system else {
        panic!("a coupled state")
    };
    assert_eq!(m.sub, 450 % 4, "saved within a body step");
    let on_body = m.contacts.iter().filter(|q| q.fs != 0.0).count();
    assert!(on_body >= 5, "{on_body} disc–body contacts with shear");
    assert_same(&a, &c);
}

/// A state saved before the first step (nothing built yet: no neighbour
/// list, no Green matrix, the implicit scheme not primed) restarts too.
#[test]
fn restarts_from_step_zero() {
    for src in [
        packing(0.0, false),
        DISC_ON_BEAM.to_string(),
        cantilever("efg"),
    ] {
        let (a, c, _) = restart(&src, 200, 0);
        assert_same(&a, &c);
    }
}

/// The same restart on 1 and 2 threads: saved on one, restored on the
/// other, and the run in one go on either, all bitwise equal.
#[test]
fn restarts_across_thread_counts() {
    for src in [
        packing(0.1, true),
        bed_on_plate("efg", ""),
        bed_on_plate("efg", "substeps = 4"),
    ] {
        let (n, k) = (500, 260);
        let mut whole = Vec::new();
        for threads in [1, 2] {
            whole.push(common::on_threads(threads, || {
                let mut a = build(&src);
                run(&mut a, n);
                a.save_state().to_bytes()
            }));
        }
        assert!(whole[0] == whole[1], "1 and 2 threads agree");
        for (save_on, resume_on) in [(1, 2), (2, 1)] {
            let bytes = common::on_threads(save_on, || {
                let mut b = build(&src);
                run(&mut b, k);
                b.save_state().to_bytes()
            });
            let end = common::on_threads(resume_on, || {
                let mut c = build(&src);
                c.restore_state(&ModelState::from_bytes(&bytes).unwrap())
                    .unwrap();
                run(&mut c, n - k);
                c.save_state().to_bytes()
            });
            assert!(
                end == whole[0],
                "saved on {save_on} thread(s), resumed on {resume_on}"
            );
        }
    }
}

/// States of another kind or size are refused with an error, and the
/// model is left as it was; bad bytes are refused.
#[test]
fn mismatched_states_are_refused() {
    let small = DISC_ON_BEAM;
    let mut coupled = build(small);
    run(&mut coupled, 3);
    let before = coupled.save_state();
    let mut granular = build(&packing(0.0, false));
    run(&mut granular, 3);
    let g_state = granular.save_state();
    // another kind
    let e = coupled.restore_state(&g_state).unwrap_err().to_string();
    assert!(e.contains("granular") && e.contains("coupled"), "{e}");
    // another disc count
    let mut fewer = build(&packing(0.0, false).replace("0.24]]", "0.12]]"));
    let e = fewer.restore_state(&g_state).unwrap_err().to_string();
    assert!(e.contains("discs"), "{e}");
    // rolling resistance switched on
    let mut rolling = build(&packing(0.1, false));
    let e = rolling.restore_state(&g_state).unwrap_err().to_string();
    assert!(e.contains("rolling"), "{e}");
    // a beam of other DOFs: refused after the discs were restored, and
    // put back
    let mut other = build(&small.replace("nodes = [20, 4]", "nodes = [21, 4]"));
    run(&mut other, 2);
    let other_before = other.save_state();
    let e = other.restore_state(&before).unwrap_err().to_string();
    assert!(e.contains("DOFs"), "{e}");
    assert!(other.save_state() == other_before, "left as it was");
    // a body of another name
    let mut renamed = build(&small.replace("\"beam\"", "\"plank\""));
    let e = renamed.restore_state(&before).unwrap_err().to_string();
    assert!(e.contains("plank"), "{e}");
    // a continuum state onto a continuum model of another method's sizes
    let efg = build(&cantilever("efg")).save_state();
    let mut fem = build(&cantilever("fem-q4"));
    let e = fem.restore_state(&efg).unwrap_err().to_string();
    assert!(e.contains("prescribed"), "{e}");
    // corrupted contents: disc ids that are not a permutation
    let mut bad = g_state.clone();
    if let SystemState::Granular(g) = &mut bad.system {
        g.id[0] = g.id[1];
    }
    let fresh = build(&packing(0.0, false));
    let mut target = build(&packing(0.0, false));
    assert!(target.restore_state(&bad).is_err());
    assert!(target.save_state() == fresh.save_state(), "left as it was");
    // bytes
    let bytes = before.to_bytes();
    assert_eq!(bytes[..4], STATE_FORMAT_VERSION.to_le_bytes());
    assert!(ModelState::from_bytes(&bytes[..bytes.len() - 3]).is_err());
    assert!(ModelState::from_bytes(&bytes[..2]).is_err());
    let mut longer = bytes.clone();
    longer.push(0);
    assert!(ModelState::from_bytes(&longer).is_err());
    let mut newer = bytes.clone();
    newer[..4].copy_from_slice(&(STATE_FORMAT_VERSION + 1).to_le_bytes());
    let e = ModelState::from_bytes(&newer).unwrap_err().to_string();
    assert!(e.contains("version"), "{e}");
    // and the good bytes restore
    let mut again = build(small);
    again
        .restore_state(&ModelState::from_bytes(&bytes).unwrap())
        .unwrap();
    assert!(again.save_state() == before);
}

// ---------------------------------------------------------------------------
// Through the drivers (`efgdem run --checkpoint-every N` / `--restart`): the
// outputs of a run of N steps and of a run checkpointed at k, then
// restarted, are byte-identical (history.csv, every frame and .pvd,
// discs_final.csv), whichever thread counts; a run stopped by a signal
// continues the same way; a changed scenario is refused.

use efgdem::run::{RunError, RunOptions};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::AtomicUsize;

#[allow(dead_code)]
mod common;

/// Output every 7 steps and frames every 50 (k is chosen to be a multiple
/// of neither), with a probe.
fn with_outputs(src: &str, probe: &str) -> String {
    format!("{src}\n[output]\nevery = 7\nvtk_every = 50\n\n[[probe]]\nname = \"p\"\n{probe}\n")
}

fn out_dir(tag: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("efgdem-restart-{tag}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    d
}

/// `efgdem::run::run` on `threads` threads.
fn drive(src: &str, threads: usize, opts: RunOptions) -> Result<serde_json::Value, RunError> {
    let sc = scenario::parse(src, "<restart>").unwrap();
    common::on_threads(threads, || efgdem::run::run(&sc, &opts))
}

fn opts(dir: &Path) -> RunOptions {
    RunOptions {
        quiet: true,
        ..RunOptions::new(dir)
    }
}

/// Every file a run wrote under `dir` except the summary (timings) and the
/// checkpoint.
fn outputs(dir: &Path) -> BTreeMap<String, Vec<u8>> {
    let mut files = BTreeMap::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                stack.push(p);
                continue;
            }
            let name = p.strip_prefix(dir).unwrap().to_string_lossy().into_owned();
            if name != "summary.json" && name != "checkpoint.bin" {
                files.insert(name, std::fs::read(&p).unwrap());
            }
        }
    }
    files
}

fn assert_same_outputs(a: &Path, b: &Path, what: &str) {
    let (fa, fb) = (outputs(a), outputs(b));
    assert_eq!(
        fa.keys().collect::<Vec<_>>(),
        fb.keys().collect::<Vec<_>>(),
        "{what}: the same files"
    );
    for (name, bytes) in &fa {
        assert!(bytes == &fb[name], "{what}: {name} differs");
    }
    assert!(fa.contains_key("history.csv") && fa.keys().any(|k| k.starts_with("frames")));
}

fn status(dir: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap()).unwrap()
}

/// The restart contract for one scenario of `n` steps, checkpointed at `k`
/// (n < 2k: the only checkpoint).
fn check_run_restart(tag: &str, src: &str, n: usize, k: usize) {
    assert!(!k.is_multiple_of(7) && !k.is_multiple_of(50) && n < 2 * k);
    let whole = out_dir(&format!("{tag}-whole"));
    let s = drive(src, 1, opts(&whole)).unwrap();
    assert_eq!(
        (s["status"].as_str(), s["last_step"].as_u64()),
        (Some("completed"), Some(n as u64))
    );
    for (t1, t2) in [(1, 2), (2, 1)] {
        let dir = out_dir(&format!("{tag}-{t1}{t2}"));
        let first = RunOptions {
            checkpoint_every: k,
            ..opts(&dir)
        };
        drive(src, t1, first).unwrap();
        let again = RunOptions {
            restart: Some(dir.join("checkpoint.bin")),
            ..opts(&dir)
        };
        let s = drive(src, t2, again).unwrap();
        assert_eq!(s["last_step"].as_u64(), Some(n as u64));
        assert_same_outputs(
            &whole,
            &dir,
            &format!("{tag}: checkpoint on {t1}, restart on {t2} thread(s)"),
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }
    // stopped by a signal (here: requested before the first step, so it
    // stops after step 1), then continued
    let dir = out_dir(&format!("{tag}-stop"));
    let stopped = RunOptions {
        stop: Some(Arc::new(AtomicUsize::new(15))),
        ..opts(&dir)
    };
    match drive(src, 2, stopped) {
        Err(RunError::Interrupted {
            signal: 15,
            step: 1,
            checkpoint,
        }) => {
            assert_eq!(checkpoint, dir.join("checkpoint.bin"))
        }
        other => panic!("{tag}: expected an interruption, got {other:?}"),
    }
    let s = status(&dir);
    assert_eq!(
        (s["status"].as_str(), s["last_step"].as_u64()),
        (Some("interrupted"), Some(1))
    );
    let again = RunOptions {
        restart: Some(dir.join("checkpoint.bin")),
        ..opts(&dir)
    };
    drive(src, 1, again).unwrap();
    assert_eq!(status(&dir)["status"].as_str(), Some("completed"));
    assert_same_outputs(&whole, &dir, &format!("{tag}: stopped at step 1"));
    // another scenario (one more step) is refused, naming the checkpoint
    let changed = src.replacen("steps = ", "steps = 1", 1);
    let again = RunOptions {
        restart: Some(dir.join("checkpoint.bin")),
        ..opts(&dir)
    };
    match drive(&changed, 1, again) {
        Err(e @ RunError::Restart { .. }) => {
            assert!(e.to_string().contains("scenario has changed"), "{e}")
        }
        other => panic!("{tag}: expected a refusal, got {other:?}"),
    }
    for d in [whole, dir] {
        std::fs::remove_dir_all(d).unwrap();
    }
}

#[test]
fn a_granular_run_restarts_with_identical_outputs() {
    // with servo and strain-rate walls and a [[measure]]'s columns
    let src = with_outputs(&packing(0.1, true), "quantity = \"kinetic\"")
        + "\n[[measure]]\nname = \"bed\"\nrectangle = [[0.05, 0.05], [0.25, 0.2]]\n";
    check_run_restart("granular", &src, 2000, 1301);
}

#[test]
fn a_run_with_clumps_restarts_with_identical_outputs() {
    // the clumps' rigid-body state is saved; discs_final.csv and the
    // frames carry the clump numbers
    let src = with_outputs(
        include_str!("common/clump_pile.toml"),
        "quantity = \"kinetic\"",
    );
    check_run_restart("clumps", &src, 3000, 1601);
}

#[test]
fn a_bonded_run_restarts_with_identical_outputs() {
    // history (bond columns), bond_breaks.csv and the crack frames
    // with a cohesion–friction shear strength
    let block = include_str!("common/bonded_block.toml")
        .replace("shear = 1.0e7", "cohesion = 8.0e6\nfriction_angle = 20");
    let src = with_outputs(&block, "quantity = \"kinetic\"");
    check_run_restart("bonded", &src, 5000, 2999);
}

#[test]
fn a_continuum_run_restarts_with_identical_outputs() {
    let src = with_outputs(&cantilever("efg"), "point = [4.0, 0.0]\nquantity = \"uy\"");
    check_run_restart("continuum", &src, 240, 131);
}

#[test]
fn a_coupled_run_restarts_with_identical_outputs() {
    let src = with_outputs(&bed_on_plate("efg", ""), "quantity = \"kinetic\"");
    check_run_restart("coupled", &src, 800, 433);
}

#[test]
fn a_restart_refuses_a_changed_discs_csv() {
    let dir = out_dir("csv");
    std::fs::create_dir_all(&dir).unwrap();
    let csv = dir.join("discs.csv");
    std::fs::write(&csv, "x,y,r\n0.05,0.05,0.004\n0.15,0.05,0.004\n").unwrap();
    let src = format!(
        r#"
[simulation]
steps = 20
gravity = [0.0, -9.81]

[[material]]
name = "sand"
density = 2650.0
kn = 1.0e6
ks = 5.0e5
friction = 0.5

[granular]
material = "sand"
discs = {{ csv = "{}" }}
damping = {{ kind = "critical-ratio", zeta = 0.2 }}

[[wall]]
name = "floor"
from = [0.0, 0.0]
to = [0.3, 0.0]
"#,
        csv.display()
    );
    let out = dir.join("out");
    let first = RunOptions {
        checkpoint_every: 11,
        ..opts(&out)
    };
    drive(&src, 1, first).unwrap();
    let again = || RunOptions {
        restart: Some(out.join("checkpoint.bin")),
        ..opts(&out)
    };
    // the same file restarts
    assert_eq!(
        drive(&src, 1, again()).unwrap()["status"].as_str(),
        Some("completed")
    );
    // one radius changed in the file, the scenario text the same: refused
    std::fs::write(&csv, "x,y,r\n0.05,0.05,0.004\n0.15,0.05,0.0041\n").unwrap();
    match drive(&src, 1, again()) {
        Err(e @ RunError::Restart { .. }) => {
            assert!(e.to_string().contains("scenario has changed"), "{e}")
        }
        other => panic!("expected a refusal, got {other:?}"),
    }
    std::fs::remove_dir_all(dir).unwrap();
}

/// [`bed_on_plate`] with an edge crack from the middle of the plate's top
/// down to mid-depth: the discs rest on the cracked top, its faces join
/// the contact chain and close under the bed (frictional face contact).
fn bed_on_cracked_plate() -> String {
    bed_on_plate("efg", "")
        + r#"
[[body.crack]]
points = [[0.1, 0.0], [0.1, -0.02]]
spacing = 0.0025
friction = 0.5
"#
}

/// A coupled run with a cracked body restarts bitwise, and runs bitwise
/// the same on 1 and 2 threads.
#[test]
fn bed_on_cracked_plate_restarts_bitwise_on_1_and_2_threads() {
    restarts_on_1_and_2_threads(&bed_on_cracked_plate(), 400, 230, |_| ());
}

/// [`restart`] of `src` (`n` steps, saved at `k`) bitwise on 1 and on 2
/// threads, the two runs bitwise the same; `check` looks at each run.
fn restarts_on_1_and_2_threads(src: &str, n: usize, k: usize, check: impl Fn(&Model) + Sync) {
    let ends: Vec<Vec<u8>> = [1, 2]
        .into_iter()
        .map(|threads| {
            common::on_threads(threads, || {
                let (a, c, _) = restart(src, n, k);
                assert_same(&a, &c);
                check(&a);
                a.save_state().to_bytes()
            })
        })
        .collect();
    assert!(ends[0] == ends[1], "1 and 2 threads agree");
}

/// [`bed_on_cracked_plate`] pulled apart by its sides, its crack growing
/// (a toughness far below its `K`, a check every 100 steps, two
/// increments of 5 mm at most).
fn bed_on_growing_plate() -> String {
    bed_on_cracked_plate()
        + r#"
[body.fracture]
toughness = 1.0e3
increment = 0.005
every = 100
max_increments = 2

[[body.bc]]
edge = "left"
traction = [-2.0e5, 0.0]
[[body.bc]]
edge = "right"
traction = [2.0e5, 0.0]
"#
}

/// The crack of body 0: its polyline's points.
fn crack_points(m: &Model) -> Vec<efgdem::Vec2> {
    match m.body(0) {
        efgdem::model::body::BodyRef::Efg(b) => b.cracks()[0].crack.points.clone(),
        _ => panic!("an EFG body"),
    }
}

/// A crack grows in a coupled run: twice, 5 mm each, downwards; the
/// contact chain is made again along the longer faces (it runs through
/// the new tip) and the discs go on resting on the plate. A restart from
/// a state saved between the two growths is bitwise the run without it,
/// and the run is bitwise the same on 1 and 2 threads.
#[test]
fn a_crack_grows_in_a_coupled_run_and_restarts_bitwise() {
    restarts_on_1_and_2_threads(&bed_on_growing_plate(), 300, 150, |a| {
        let pts = crack_points(a);
        eprintln!("crack {pts:?}");
        let tip = *pts.last().unwrap();
        // two pieces of 5 mm, downwards (the bed's uneven
        // load kinks the second by a few degrees)
        assert_eq!(pts.len(), 4, "two increments");
        for w in pts[1..].windows(2) {
            assert!(((w[1] - w[0]).norm() - 0.005).abs() < 1e-12);
            assert!((w[1] - w[0]).y < -0.0045, "downwards");
        }
        let chain = &a.coupled().unwrap().bodies[0].contact_boundary()[0];
        assert!(chain.reference.contains(&tip), "the chain runs to the tip");
        let on_body = a
            .contacts()
            .iter()
            .filter(|c| c.kind == efgdem::model::ContactKind::DiscBody)
            .count();
        assert!(on_body >= 5, "{on_body} discs on the plate");
        // none fell into the plate through the rebuilt chain
        let p = &a.granular().unwrap().particles;
        let low = p.pos.iter().map(|x| x.y).fold(f64::MAX, f64::min);
        assert!(low > 0.003, "a disc at y = {low}");
    });
}
