//! The continuum and coupled benchmark cases, shared by
//! `benches/body_step.rs` (criterion) and `examples/body_threads.rs`
//! (1 against 2 threads, interleaved):
//!
//! * the EFG plate: N × N nodes on a unit square (201 × 201: 80 802 DOFs,
//!   4 × 4 Gauss points per cell), steel, mass-proportional damping,
//!   clamped on the left, loaded on the right; one Newmark step;
//! * the coupled footing: a concrete strip footing 0.3 m wide, 0.1 m high,
//!   EFG 61 × 21 nodes (2 562 DOFs), its top edge driven down at 0.1 m/s
//!   into a bed of 20 000 discs (r = 4 mm, hexagonal lattice under
//!   gravity, k_n = 5·10⁷, k_s = 2.5·10⁷, μ = 0.5, normal dashpot at 20 %
//!   of critical), Δt = 10⁻⁵ s; one coupled step, exact (`substeps = 1`),
//!   sub-cycled, or as the automatic choice takes it (`substeps = 0`: no
//!   key).
#![allow(dead_code)]

use efgdem::coupling::CoupledModel;
use efgdem::efg::EfgBody;
use efgdem::scenario;

/// The plate of `n × n` nodes, ready to step.
pub fn plate(n: usize) -> EfgBody {
    let src = format!(
        r#"
[simulation]
analysis = "dynamic"
dt = 1e-4
steps = 1
[[body]]
name = "plate"
rectangle = {{ origin = [0.0, 0.0], size = [1.0, 1.0] }}
nodes = [{n}, {n}]
gauss = 4
elastic = {{ E = 2.0e11, nu = 0.3, density = 7800.0, plane = "strain" }}
damping = 10.0
[[body.bc]]
edge = "left"
fixed = true
[[body.bc]]
edge = "right"
traction = [0.0, -1.0e6]
"#
    );
    let sc = scenario::parse(&src, "plate.toml").expect("valid scenario");
    let mut b = EfgBody::new(&sc.body[0].params(), sc.simulation.gravity).expect("build");
    b.start_dynamic(1e-4).expect("factor");
    b
}

/// The coupled footing with `substeps` DEM steps per body step (0: the
/// automatic choice of scheme and substeps), its bottom starting 1 % of a radius into the top row of discs, after `warm`
/// steps.
pub fn footing(substeps: usize, warm: usize) -> CoupledModel {
    let substeps = match substeps {
        0 => String::new(),
        n => format!("substeps = {n}"),
    };
    let (r, width) = (0.004, 1.6);
    let depth = 100.0 * 3f64.sqrt() * r;
    let bed = format!(
        r#"
[simulation]
dt = 1.0e-5
steps = 1
{substeps}
gravity = [0.0, -9.81]

[[material]]
name = "sand"
density = 2650.0
kn = 5.0e7
ks = 2.5e7
friction = 0.5

[granular]
material = "sand"
discs = {{ generate = "hex", box = [[0.0, 0.0], [{width}, {depth}]], radius = {r} }}
damping = {{ kind = "critical-ratio", zeta = 0.2 }}
allow_overlap = true

[[wall]]
name = "floor"
from = [0.0, 0.0]
to = [{width}, 0.0]

[[wall]]
name = "left"
from = [0.0, 0.0]
to = [0.0, 1.0]

[[wall]]
name = "right"
from = [{width}, 0.0]
to = [{width}, 1.0]
"#
    );
    let sc = scenario::parse(&bed, "bed.toml").expect("bed scenario");
    let g = sc.build().expect("bed").into_granular().expect("granular");
    let p = &g.particles;
    let top = (0..p.len())
        .map(|k| p.pos[k].y + p.radius[k])
        .fold(f64::MIN, f64::max);
    let src = bed
        + &format!(
            r#"
[[body]]
name = "footing"
rectangle = {{ origin = [0.65, {y0}], size = [0.3, 0.1] }}
nodes = [61, 21]
elastic = {{ E = 30.0e9, nu = 0.2, density = 2400.0, plane = "strain" }}
newmark = {{ gamma = 0.5, beta = 0.25 }}
self_weight = false
[[body.bc]]
edge = "top"
ux = 0.0
uy = {{ velocity = -0.1 }}
"#,
            y0 = top - 0.01 * r
        );
    let sc = scenario::parse(&src, "footing.toml").expect("footing scenario");
    let mut m = sc
        .build()
        .expect("coupled model")
        .into_coupled()
        .expect("coupled");
    for _ in 0..warm {
        m.step().expect("step");
    }
    m
}
