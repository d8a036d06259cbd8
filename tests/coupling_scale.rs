//! Issue 10, validation 2: the implicit contact step through the boundary
//! Green matrix (`contact_solve = "boundary"`, the default: no solve per
//! contact, GMRES above 48 contacts) gives the same contact forces as the
//! reference step that computes `A⁻¹Φᵀ` by two solves per contact
//! (`contact_solve = "direct"`), to 1e-8 relative, on Example 1, the
//! nine-disc tests (EFG and FE plates) and a footing pressed into a bed
//! with ~100 simultaneous contacts.

use efgdem::coupling::CoupledModel;
use efgdem::geom::Vec2;
use efgdem::scenario::parse;

#[allow(dead_code)]
mod common;

fn model(src: &str, direct: bool) -> CoupledModel {
    let src = if direct {
        src.replacen(
            "[simulation]",
            "[simulation]\ncontact_solve = \"direct\"",
            1,
        )
    } else {
        src.to_string()
    };
    parse(&src, "test.toml")
        .expect("scenario")
        .build()
        .expect("model")
        .into_coupled()
        .unwrap()
}

/// Step both models `steps` times; the largest difference of any disc–body
/// contact force over the run, relative to the largest force, and the
/// largest number of simultaneous contacts.
fn compare(src: &str, steps: usize) -> (f64, usize) {
    let (mut a, mut b) = (model(src, false), model(src, true));
    let (mut diff, mut scale, mut most) = (0.0f64, 0.0f64, 0);
    for _ in 0..steps {
        a.step().expect("boundary step");
        b.step().expect("direct step");
        assert_eq!(a.contacts.len(), b.contacts.len(), "same contacts");
        most = most.max(a.contacts.len());
        for (p, q) in a.contacts.iter().zip(&b.contacts) {
            assert_eq!((p.disc, p.body, p.chain), (q.disc, q.body, q.chain));
            diff = diff.max((p.force - q.force).norm());
            scale = scale.max(q.force.norm());
        }
    }
    assert!(scale > 0.0, "the run must have contacts");
    (diff / scale, most)
}

fn example(name: &str) -> String {
    let path = format!("{}/examples/{name}", env!("CARGO_MANIFEST_DIR"));
    std::fs::read_to_string(&path).expect("example")
}

#[test]
fn example_1_boundary_equals_direct() {
    // 200 steps from the disc's release (it lands at once)
    let (rel, _) = compare(&example("paper_cantilever_disc.toml"), 200);
    assert!(rel < 1e-8, "Example 1: {rel:e}");
}

/// The plates are very stiff (E = 2.1e14, penalty 10⁵ E on the driven
/// edges) and push the discs with 7e7 N: the two schemes differ by
/// round-off (1e-14 of the force at the first steps), which the run
/// amplifies, and once a contact-law threshold (stick/slide, no tension)
/// goes one way in one run and the other way in the other, the forces jump
/// apart by a few newtons (EFG: 13 N at step ~48; FE: 2.9 N at step 128,
/// i.e. 2e-7 and 4e-8): ties broken by round-off, not a difference of the
/// schemes. So each run is compared up to just before its first such event
/// — the whole loading phase (40 steps) for the EFG plates.
#[test]
fn nine_disc_tests_boundary_equal_direct() {
    for (f, steps) in [
        ("paper_nine_disc_test1.toml", 42),
        ("paper_nine_disc_test2.toml", 42),
        ("fem_nine_disc_test1.toml", 125),
    ] {
        let (rel, _) = compare(&example(f), steps);
        assert!(rel < 1e-8, "{f}: {rel:e}");
    }
}

/// A concrete footing (EFG, 64 × 8 nodes, all edges in contact, top edge
/// driven down) on a hexagonal bed, pressed 1 % of a radius into its top
/// row: about 100 contacts at once.
fn footing_on_a_bed() -> String {
    let r = 0.005;
    let (w, width) = (100.0 * 2.0 * r, 1.8);
    let depth = 6.0 * 3f64.sqrt() * r + 2.0 * r;
    let bed = format!(
        r#"
[simulation]
dt = 4.0e-5
steps = 1
gravity = [0.0, -9.81]
[[material]]
name = "grain"
density = 2650.0
kn = 1.0e7
ks = 1.0e7
friction = 0.5
[granular]
material = "grain"
discs = {{ generate = "hex", box = [[0.0, 0.0], [{width}, {depth}]], radius = {r} }}
damping = {{ kind = "critical-ratio", zeta = 0.2 }}
# the footing starts pressed 1 % of a radius into the top row (over 60
# contacts from the first step)
allow_overlap = true
[[wall]]
name = "floor"
from = [0.0, 0.0]
to = [{width}, 0.0]
"#
    );
    let g = parse(&bed, "bed.toml")
        .expect("scenario")
        .build()
        .expect("bed")
        .into_granular()
        .unwrap();
    let top = g
        .particles
        .pos
        .iter()
        .zip(&g.particles.radius)
        .map(|(p, r)| p.y + r)
        .fold(f64::MIN, f64::max);
    bed + &format!(
        r#"
[[body]]
name = "footing"
rectangle = {{ origin = [{x0}, {y0}], size = [{w}, 0.1] }}
nodes = [64, 8]
elastic = {{ E = 30.0e9, nu = 0.2, density = 2400.0, thickness = 1.0, plane = "strain" }}
newmark = {{ gamma = 0.5, beta = 0.25 }}
self_weight = false
[[body.bc]]
edge = "top"
ux = 0.0
uy = {{ velocity = -0.05 }}
"#,
        x0 = (width - w) / 2.0,
        y0 = top - 0.01 * r,
    )
}

/// The GMRES path (> 48 contacts) against the direct scheme.
#[test]
fn footing_with_a_hundred_contacts_boundary_equals_direct() {
    let (rel, most) = compare(&footing_on_a_bed(), 60);
    assert!(most > 60, "the GMRES path needs > 48 contacts (got {most})");
    assert!(rel < 1e-8, "footing: {rel:e}");
}

/// The contact forces and disc positions after 40 steps of `src` on
/// `threads` threads.
fn run_on(src: &str, threads: usize) -> (Vec<(u32, Vec2)>, Vec<Vec2>) {
    common::on_threads(threads, || {
        let mut m = model(src, false);
        for _ in 0..40 {
            m.step().expect("step");
        }
        let forces: Vec<_> = m.contacts.iter().map(|c| (c.disc, c.force)).collect();
        (forces, m.granular.particles.pos.clone())
    })
}

/// 1 and 2 threads give bitwise the same coupled run (boundary Green
/// matrix built in parallel blocks, products by rows, DEM sweep).
#[test]
fn footing_is_bitwise_independent_of_the_thread_count() {
    let src = footing_on_a_bed();
    let (a, b) = (run_on(&src, 1), run_on(&src, 2));
    assert!(a.0.len() > 60);
    assert_eq!(a, b);
}

/// The same for the sub-cycled scheme (10 DEM steps per body step, four
/// body steps): the path, its loads and the grids binned once per body
/// step do not depend on the thread count.
#[test]
fn subcycled_footing_is_bitwise_independent_of_the_thread_count() {
    let src = footing_on_a_bed().replace("[[material]]", "substeps = 10\n[[material]]");
    assert!(model(&src, false).path_scheme());
    let (a, b) = (run_on(&src, 1), run_on(&src, 2));
    assert!(a.0.len() > 60);
    assert_eq!(a, b);
}

/// An exact step that leaves its body step's end (the contacts' response
/// and the commit) to the next step, and a compliant step within a body
/// step that leaves its contact solve to the next step, done beside the
/// discs' step (`Model::step_deferring`, as `efgdem run` steps between
/// outputs), give bitwise the steps of `Model::step`, with a settle in
/// between (an output) or not, on 1 and 2 threads.
#[test]
fn deferred_body_ends_give_the_same_steps() {
    for coupling in [
        "coupling = \"exact\"",
        "coupling = \"compliant\"\nsubsteps = 5",
    ] {
        let src = footing_on_a_bed().replace("[[material]]", &format!("{coupling}\n[[material]]"));
        let build =
            || -> efgdem::model::Model { parse(&src, "test.toml").unwrap().build().unwrap() };
        let mut want = build();
        for _ in 0..40 {
            want.step().unwrap();
        }
        assert!(
            want.coupled().unwrap().contacts.len() > 30,
            "{coupling}: contacts"
        );
        let want = want.save_state().to_bytes();
        for threads in [1, 2] {
            let got = common::on_threads(threads, || {
                let mut m = build();
                let mut pending = 0;
                for step in 1..=40 {
                    m.step_deferring().unwrap();
                    pending += usize::from(!m.coupled().unwrap().is_settled());
                    if step == 20 {
                        m.settle().unwrap();
                    }
                }
                m.settle().unwrap();
                assert!(m.coupled().unwrap().is_settled());
                // the compliant step defers on several threads only, and
                // not the last step of a body step
                let least = if coupling.contains("exact") {
                    30
                } else {
                    25 * (threads - 1)
                };
                assert!(
                    pending >= least,
                    "{coupling}: steps left pending: {pending}"
                );
                m.save_state().to_bytes()
            });
            assert!(got == want, "{coupling}, {threads} threads");
        }
    }
}
