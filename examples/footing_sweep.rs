//! Cost of the coupled step against the DEM step on the same bed
//! (manual: docs/performance.md, "Coupled steps"):
//! an EFG strip footing pressed into a bed of discs, for footing widths that
//! give about 10, 100, 1 000 and 5 000 simultaneous disc–footing contacts
//! and footing bodies of about 1 000 and 10 000 nodes.
//!
//! The bed is a hexagonal lattice of equal discs (r = 5 mm, ρ = 2650 kg/m³,
//! k_n = k_s = 10⁷ N/m, μ = 0.5, normal dashpot at 20 % of critical) under
//! gravity in a box 1.5 × the footing width (at least 40 diameters more)
//! and 17 rows deep: it needs no deposit, and its top row is flat, so the
//! footing bottom touches one disc per diameter. The footing (concrete:
//! E = 30 GPa, ν = 0.2, ρ = 2400 kg/m³, plane strain, height W/10, all
//! edges in contact) starts 1 % of a radius into the top row and its top
//! edge is driven down at 5 cm/s. Each case runs `warm` steps (the first
//! one with contacts builds the body's boundary Green matrix: timed
//! apart as start-up) and then `steps` timed steps, coupled and DEM only.
//!
//! With `NO_GEOMETRIC_STIFFNESS` set in the environment the contacts'
//! geometric stiffness stays explicit (`geometric_stiffness = false`).
//!
//! With `BED=similar` the bed is instead 6 footing widths wide and 1.8
//! deep, the proportions of `examples/strip_footing.toml` (a bed that holds
//! a footing's failure mechanism): the number of discs then grows with the
//! square of the footing width (1.25·10⁷ discs at 1 000 contacts, ≈ 4 GiB).
//!
//!     cargo run --release --example footing_sweep -- [threads] [steps] [contacts,...] [nodes,...]
//!     cargo run --release --example footing_sweep -- 2 100 10,100,1000,5000 1000,10000
//!     BED=similar cargo run --release --example footing_sweep -- 2 50 10,100,1000 1000,10000
//!
//! `BED=rows:N` keeps the shallow bed's width with N rows instead of 17.
//!
//! `SUBSTEPS=n` runs the sub-cycled scheme (`[simulation] substeps = n`:
//! one body step per n DEM steps, the boundary on its predicted path, no
//! contact solve) instead of the exact implicit step.
//!
//! With `NO_GRAVITY` set the bed has no gravity: the lattice touches with no
//! force and stays put. Under gravity a deep bed falls freely until the
//! floor's compression wave (≈ 2 km/s) reaches its top, 1.6 ms after the
//! start in a bed 790 rows (6.8 m) deep, so its top discs fall away from a
//! footing whose bottom starts moving only once the drive's wave has
//! crossed it: 5 000 diameters of footing then touch ≈ 1 250–3 100 discs
//! instead of ≈ 5 000.

use efgdem::scenario;
use std::time::Instant;

const R: f64 = 0.005;

fn bed(width: f64, depth: f64, gravity: f64) -> String {
    format!(
        r#"
[simulation]
dt = 4.0e-5
steps = 1
gravity = [0.0, {gravity}]

[[material]]
name = "grain"
density = 2650.0
kn = 1.0e7
ks = 1.0e7
friction = 0.5

[granular]
material = "grain"
discs = {{ generate = "hex", box = [[0.0, 0.0], [{width}, {depth}]], radius = {R} }}
damping = {{ kind = "critical-ratio", zeta = 0.2 }}
allow_overlap = true   # the footing starts 1 % of a radius into the top row

[[wall]]
name = "floor"
from = [0.0, 0.0]
to = [{width}, 0.0]

[[wall]]
name = "left"
from = [0.0, 0.0]
to = [0.0, {depth2}]

[[wall]]
name = "right"
from = [{width}, 0.0]
to = [{width}, {depth2}]
"#,
        depth2 = 3.0 * depth
    )
}

fn footing(x0: f64, y0: f64, w: f64, nodes: usize) -> String {
    let h = w / 10.0;
    let nx = ((10.0 * nodes as f64).sqrt().round() as usize).max(4);
    let ny = ((nodes as f64 / nx as f64).round() as usize).max(3);
    format!(
        r#"
[[body]]
name = "footing"
rectangle = {{ origin = [{x0}, {y0}], size = [{w}, {h}] }}
nodes = [{nx}, {ny}]
elastic = {{ E = 30.0e9, nu = 0.2, density = 2400.0, thickness = 1.0, plane = "strain" }}
newmark = {{ gamma = 0.5, beta = 0.25 }}
self_weight = false
contact_edges = ["bottom", "right", "top", "left"]
[[body.bc]]
edge = "top"
ux = 0.0
uy = {{ velocity = -0.05 }}
"#
    )
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let threads: usize = args.get(1).and_then(|s| s.parse().ok()).unwrap_or(2);
    let steps: usize = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(100);
    let list = |i: usize, d: &str| -> Vec<usize> {
        args.get(i)
            .map_or(d, |s| s.as_str())
            .split(',')
            .filter_map(|x| x.parse().ok())
            .collect()
    };
    let contacts = list(3, "10,100,1000,5000");
    let nodes = list(4, "1000,10000");
    // SUBSTEPS=n: the sub-cycled scheme, one body step per n DEM steps
    // (warm-up and timed steps are whole body steps)
    let substeps: usize = std::env::var("SUBSTEPS")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(1);
    let warm = 20usize.next_multiple_of(substeps).max(2 * substeps);
    let steps = steps.next_multiple_of(substeps);
    let bed_kind = std::env::var("BED").unwrap_or_default();
    let similar = bed_kind == "similar";
    let rows_given: Option<f64> = bed_kind.strip_prefix("rows:").and_then(|r| r.parse().ok());
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("thread pool");
    pool.install(|| {
        println!(
            "threads {threads}, {steps} timed steps after {warm}\n\
             | contacts (target) | discs | footing nodes (DOFs) | contacts (mean) | |B| | G MiB | start-up s | DEM-only ms/step | coupled ms/step | ratio | split DEM / transfer / contact solve / body solve (ms/step) |\n\
             |---|---|---|---|---|---|---|---|---|---|---|"
        );
        for &nc in &contacts {
            let w = nc as f64 * 2.0 * R;
            let rows = if similar {
                (1.8 * w / (3f64.sqrt() * R)).round()
            } else {
                rows_given.unwrap_or(17.0)
            };
            let width = if similar { 6.0 * w } else { 1.5 * w + 80.0 * R };
            let depth = rows * 3f64.sqrt() * R + 2.0 * R;
            let gravity = if std::env::var("NO_GRAVITY").is_ok() {
                0.0
            } else {
                -9.81
            };
            let bed_src = bed(width, depth, gravity);
            // the bed alone: DEM-only timing, and the height of its top row
            let sc = scenario::parse(&bed_src, "bed.toml").expect("bed scenario");
            let mut g = sc.build().expect("bed").into_granular().unwrap();
            let top = g
                .particles
                .pos
                .iter()
                .zip(&g.particles.radius)
                .map(|(p, r)| p.y + r)
                .fold(f64::MIN, f64::max);
            let n_discs = g.particles.len();
            eprintln!("  bed of {n_discs} discs built");
            for _ in 0..warm {
                g.step();
            }
            let t = Instant::now();
            for _ in 0..steps {
                g.step();
            }
            let dem_ms = t.elapsed().as_secs_f64() * 1e3 / steps as f64;
            drop(g);
            for &nn in &nodes {
                let src = bed_src.replace("steps = 1\n", &format!("steps = 1\nsubsteps = {substeps}\n"))
                    + &footing((width - w) / 2.0, top - 0.01 * R, w, nn);
                let sc = scenario::parse(&src, "footing.toml").expect("footing scenario");
                let mut m = sc.build().expect("coupled model").into_coupled().unwrap();
                m.geometric_stiffness = std::env::var("NO_GEOMETRIC_STIFFNESS").is_err();
                let dofs = 2 * sc.body[0].nodes[0] * sc.body[0].nodes[1];
                let t0 = Instant::now();
                m.step().expect("first step");
                let startup = t0.elapsed().as_secs_f64();
                for _ in 1..warm {
                    m.step().expect("step");
                }
                let before = m.timing;
                let p0 = m.compliance_products;
                let mut touching = 0usize;
                let t = Instant::now();
                for _ in 0..steps {
                    m.step().expect("step");
                    touching += m.contacts.len();
                }
                let ms = t.elapsed().as_secs_f64() * 1e3 / steps as f64;
                let per = |a: f64, b: f64| (a - b) * 1e3 / steps as f64;
                let (nb, bytes) = m.bodies[0].green_size();
                eprintln!(
                    "  products S x per step {:.1}",
                    (m.compliance_products - p0) as f64 / steps as f64
                );
                println!(
                    "| {nc} | {n_discs} | {}×{} ({dofs}) | {:.0} | {nb} | {:.1} | {startup:.2} | {dem_ms:.3} | {ms:.3} | {:.2} | {:.3} / {:.3} / {:.3} / {:.3} |",
                    sc.body[0].nodes[0],
                    sc.body[0].nodes[1],
                    touching as f64 / steps as f64,
                    bytes as f64 / (1 << 20) as f64,
                    ms / dem_ms,
                    per(m.timing.dem, before.dem),
                    per(m.timing.transfer, before.transfer),
                    per(m.timing.contact_solve, before.contact_solve),
                    per(m.timing.body, before.body),
                );
            }
        }
    });
}
