//! Discs inside open cracks: the crack faces are on the body's contact
//! chains, and a disc that meets a face rebounds from it as from a rigid
//! wall of the same geometry — the analytic rebound of a linear spring.

use efgdem::Vec2;
use efgdem::coupling::CoupledModel;
use efgdem::model::Model;
use efgdem::scenario;

const KN: f64 = 1.0e5;
/// The body's Young modulus: 10⁵ × the contact stiffness (thickness 1).
const E: f64 = 1.0e10;
const R: f64 = 0.01;
const DT: f64 = 5.0e-5;

/// A unit square ([`E`], plane strain) on rollers (left `ux = 0`,
/// bottom `uy = 0`), pulled by `strain × E` on its right side, with `crack`
/// (TOML points), started from its static equilibrium (the crack open);
/// one frictionless, undamped disc of radius [`R`] at `at` moving at `v`,
/// no gravity.
fn scenario(crack: &str, strain: f64, at: Vec2, v: Vec2) -> Model {
    let sigma = strain * E;
    let src = format!(
        r#"
[simulation]
dt = {DT}
steps = 1
gravity = [0.0, 0.0]

[[material]]
name = "m"
density = 1000.0
kn = {KN}
ks = {KN}
friction = 0.0

[granular]
material = "m"
discs = [[{}, {}, {R}]]
velocity = [{}, {}]

[[body]]
name = "plate"
method = "efg"
rectangle = {{ origin = [0.0, 0.0], size = [1.0, 1.0] }}
nodes = [11, 11]
elastic = {{ E = {E}, nu = 0.2, density = 2000.0, plane = "strain" }}
initial = {{ static_under = [] }}

[[body.crack]]
points = {crack}
spacing = 0.025

[[body.bc]]
edge = "left"
ux = 0.0
[[body.bc]]
edge = "bottom"
uy = 0.0
[[body.bc]]
edge = "right"
traction = [{sigma}, 0.0]
"#,
        at.x, at.y, v.x, v.y
    );
    scenario::parse(&src, "crack_discs.toml")
        .unwrap()
        .build()
        .unwrap()
}

/// One contact of the disc with the body.
struct Bounce {
    /// Disc position and velocity at the last step without the contact.
    x0: Vec2,
    v0: Vec2,
    /// The body's contact chains then (current positions).
    chains: Vec<Vec<Vec2>>,
    /// Disc velocity at the first step without it after.
    after: Vec2,
    /// Steps in contact, and the largest overlap.
    steps: usize,
    overlap: f64,
    /// Contact normal (towards the body) at the first step of contact.
    normal: Vec2,
}

fn disc(m: &CoupledModel) -> (Vec2, Vec2) {
    let p = &m.granular.particles;
    (p.pos[0], p.vel[0])
}

fn chains(m: &CoupledModel) -> Vec<Vec<Vec2>> {
    m.bodies[0]
        .contact_boundary()
        .iter()
        .map(|c| c.current.clone())
        .collect()
}

/// Step until `done(bounces so far, disc position, velocity)` once the disc
/// is free (at most `max` steps): its bounces off the body.
fn bounces(
    m: &mut CoupledModel,
    done: impl Fn(&[Bounce], Vec2, Vec2) -> bool,
    max: usize,
) -> Vec<Bounce> {
    let mut out: Vec<Bounce> = Vec::new();
    let mut open = false;
    let (mut x, mut v) = disc(m);
    let mut before = chains(m);
    for _ in 0..max {
        m.step().unwrap();
        let (x1, v1) = disc(m);
        let touch: Vec<_> = m.contacts.iter().filter(|c| c.overlap > 0.0).collect();
        assert!(touch.len() <= 1, "one face at a time");
        match (touch.first(), open) {
            (Some(t), false) => out.push(Bounce {
                x0: x,
                v0: v,
                chains: std::mem::take(&mut before),
                after: v1,
                steps: 1,
                overlap: t.overlap,
                normal: t.normal,
            }),
            (Some(t), true) => {
                let b = out.last_mut().unwrap();
                b.steps += 1;
                b.overlap = b.overlap.max(t.overlap);
            }
            (None, true) => out.last_mut().unwrap().after = v1,
            (None, false) => {}
        }
        open = !touch.is_empty();
        if !open {
            before = chains(m);
        }
        (x, v) = (x1, v1);
        if !open && done(&out, x, v) {
            return out;
        }
    }
    panic!("not done after {max} steps: the disc at {x:?}");
}

/// Each bounce is the rigid wall's: the velocity after it is that of the
/// same disc against the chains held rigid ([`rigid`]) within 2e-5 of its
/// speed (the body is 10⁵ times stiffer than the contact spring; with
/// E = 10⁹ and 10¹¹ the differences are 1.3e-3 and 2.4e-7: the body's
/// give), the contact lasts as long and the linear spring's half period
/// `π √(m/k_n)` to a step, and its largest overlap is `|v_n| √(m/k_n)`
/// within 5e-4 (the peak sampled at steps: (ωΔt)²/8 = 1e-4 at most below
/// it). Returns the contact normals.
fn check_rigid(m: &CoupledModel, b: &[Bounce]) -> Vec<Vec2> {
    let mass = m.granular.particles.mass[0];
    let w = (KN / mass).sqrt();
    let half_period = std::f64::consts::PI / w / DT;
    for (k, b) in b.iter().enumerate() {
        let (v_rigid, steps_rigid) = rigid(&b.chains, b.x0, b.v0, mass);
        let err = (b.after - v_rigid).norm() / b.v0.norm();
        let vn = b.v0.dot(b.normal);
        eprintln!(
            "bounce {k} from {:?}: normal {:?}, v {:?} -> {:?} (rigid: {err:.2e} off), {} steps (rigid {steps_rigid}, π√(m/k)/Δt {half_period:.1}), overlap {:.5e} (|v_n|√(m/k) {:.5e})",
            b.x0,
            b.normal,
            b.v0,
            b.after,
            b.steps,
            b.overlap,
            vn / w
        );
        assert!(err < 2e-5, "bounce {k}: {err:.2e} off the rigid wall");
        assert_eq!(b.steps, steps_rigid, "bounce {k}");
        assert!((b.steps as f64 - half_period).abs() < 1.0, "bounce {k}");
        assert!(
            (b.overlap / (vn / w) - 1.0).abs() < 5e-4,
            "bounce {k}: overlap"
        );
    }
    b.iter().map(|b| b.normal).collect()
}

/// The same disc against the chains held rigid: the closest point `H` of
/// the chains, the linear spring `k_n (r − |x − H|)` along `(x − H)/|x − H|`,
/// the DEM's central differences. From `x0`, `v0` to the first step without
/// contact: the velocity then and the steps in contact.
fn rigid(chains: &[Vec<Vec2>], x0: Vec2, v0: Vec2, mass: f64) -> (Vec2, usize) {
    let (mut x, mut v, mut steps) = (x0, v0, 0);
    loop {
        let mut h = (f64::MAX, Vec2::ZERO);
        for w in chains.iter().flat_map(|c| c.windows(2)) {
            let t = w[1] - w[0];
            let q = w[0] + t * ((x - w[0]).dot(t) / t.norm2()).clamp(0.0, 1.0);
            if (x - q).norm() < h.0 {
                h = ((x - q).norm(), q);
            }
        }
        let f = if h.0 < R {
            (x - h.1) * (KN * (R - h.0) / h.0)
        } else {
            Vec2::ZERO
        };
        v += f * (DT / mass);
        x += v * DT;
        if f == Vec2::ZERO && steps > 0 {
            return (v, steps - 1);
        }
        steps += 1;
    }
}

/// A disc thrown into the open mouth of an edge crack bounces from face to
/// face and out again, each bounce the rigid wall's ([`check_rigid`]).
#[test]
fn a_disc_in_an_open_edge_crack_is_pushed_out_as_by_a_rigid_wall() {
    let mut m = scenario(
        "[[0.5, 1.0], [0.5, 0.5]]",
        0.02,
        Vec2::new(0.51, 1.03),
        Vec2::new(1.0, -1.0),
    )
    .into_coupled()
    .unwrap();
    // the static tension opens the mouth to 0.11 (5 diameters)
    let mouth: Vec<Vec2> = (m.bodies[0].contact_boundary().iter())
        .flat_map(|c| c.reference.iter().zip(&c.current))
        .filter(|(r, _)| (**r - Vec2::new(0.5, 1.0)).norm() < 1e-6)
        .map(|(_, c)| *c)
        .collect();
    let opening = (mouth[0] - mouth[mouth.len() - 1]).norm();
    assert!((0.1..0.12).contains(&opening), "mouth open by {opening}");
    let out = |_: &[Bounce], x: Vec2, v: Vec2| x.y > 1.05 && v.y > 0.0;
    let b = bounces(&mut m, out, 40000);
    eprintln!("{} bounces, out at {:?}", b.len(), disc(&m));
    // docs/howto/cracks.md: "bounces ten times from face to face"
    assert!(b.len() >= 10, "{} bounces", b.len());
    for (k, n) in check_rigid(&m, &b).iter().enumerate() {
        // inside the crack, on the right face first, then face to face
        assert!(b[k].x0.y < 1.0, "inside the crack");
        assert_eq!(n.x > 0.0, k % 2 == 0, "faces in turn");
    }
    // out of the mouth, moving away, touching nothing
    let (x, v) = disc(&m);
    assert!(x.y > 1.05 && v.y > 0.5, "{x:?} {v:?}");
    assert!(m.contacts.iter().all(|c| c.overlap <= 0.0));
}

/// The faces of a crack with two tips are a closed chain of their own: a
/// disc inside the open crack (put there after the start, as the
/// scenario's start check refuses a disc inside the undeformed body)
/// bounces between them as between rigid walls ([`check_rigid`]).
#[test]
fn a_disc_in_an_open_internal_crack_bounces_between_its_faces() {
    let m = scenario(
        "[[0.5, 0.3], [0.5, 0.7]]",
        0.1,
        Vec2::new(2.0, 2.0),
        Vec2::new(1.0, 0.2),
    );
    let CoupledModel {
        mut granular,
        bodies,
        ..
    } = m.into_coupled().unwrap();
    assert_eq!(bodies[0].contact_boundary().len(), 2, "outline and crack");
    // in the middle of the opening (the crack moves with the stretched
    // plate, and opens to 0.085)
    let face = &bodies[0].contact_boundary()[1].current;
    let x = face.iter().map(|p| p.x).sum::<f64>() / face.len() as f64;
    granular.particles.pos[0] = Vec2::new(x, 0.5);
    let mut m = CoupledModel::new(granular, bodies, &[None], 1);
    let six = |b: &[Bounce], _: Vec2, _: Vec2| b.len() == 6;
    let b = bounces(&mut m, six, 40000);
    for (k, n) in check_rigid(&m, &b).iter().enumerate() {
        assert_eq!(n.x > 0.0, k % 2 == 0, "faces in turn");
    }
    // the disc stayed in the crack: it touched its chain only
    assert!(m.contacts.iter().all(|c| c.chain == 1));
}

/// `examples/cracking_beam.toml` for its first 0.08 s: the bed falls on
/// the beam and bends it, and the notch in the middle of the tension face
/// (the bottom) grows upwards, towards the compression side, into the
/// upper fifth of the depth.
#[test]
fn the_beam_example_cracks_from_its_tension_face_upwards() {
    let src = std::fs::read_to_string("examples/cracking_beam.toml").unwrap();
    let mut m = scenario::parse(&src, "examples/cracking_beam.toml")
        .unwrap()
        .build()
        .unwrap();
    for _ in 0..4000 {
        m.step().unwrap();
    }
    let pts = match m.body(0) {
        efgdem::model::body::BodyRef::Efg(b) => b.cracks()[0].crack.points.clone(),
        _ => panic!("an EFG beam"),
    };
    eprintln!("crack: {pts:?}");
    assert_eq!(pts[0], Vec2::new(0.5, 0.0), "the mouth on the bottom");
    // through most of the depth: the tip in its upper fifth
    assert!(pts.last().unwrap().y > 0.08, "{pts:?}");
    for w in pts.windows(2) {
        let d = w[1] - w[0];
        // upwards, within 60° of the vertical everywhere, within 10° in
        // the lower half (bending: mode I); near the top the compression
        // zone and the clamp's asymmetry turn it (the last piece by 31°)
        let tilt = d.x.atan2(d.y).to_degrees().abs();
        let bound = if w[1].y <= 0.05 { 10.0 } else { 60.0 };
        assert!(tilt < bound, "piece {d:?} at {tilt:.1}°");
    }
}
