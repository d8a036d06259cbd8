//! The DEM benchmark packings, shared by `benches/dem_step.rs` and
//! `examples/dem_peer.rs` (the efgdem side of the peer benchmark in
//! `bench/peers/`): polydisperse discs (r uniform in [0.8, 1.2], ρ = 1,
//! k_n = k_s = 10⁶, friction 0.5, normal dashpot at ζ = 0.2, gravity)
//! in a closed box.
//!
//! The dense packing is made once by gravity deposition and cached in
//! `target/dem-bench-cache/dense_N.csv`.
#![allow(dead_code)]

use efgdem::Vec2;
use efgdem::dem::Granular;
use efgdem::dem::contact::ContactLaw;
use efgdem::dem::packing::{DiscRow, Lattice, lattice_packing, settle_in_box};
use efgdem::dem::particles::Particles;
use efgdem::dem::walls::{Wall, WallMotion};
use efgdem::scenario::generate::discs_from_csv;
use std::path::PathBuf;

/// The contact law without dashpots (k_n = k_s = 10⁶, μ = 0.5).
pub fn law() -> ContactLaw {
    ContactLaw {
        kn: 1.0e6,
        ks: 1.0e6,
        mu: 0.5,
        ..Default::default()
    }
}

/// Box for n discs: a wide bed (width 2.64 · 4√n, about n/(1.5√n) rows),
/// tall enough for the loose packing.
pub fn bounds(n: usize) -> (Vec2, Vec2) {
    let w = 2.64 * 4.0 * (n as f64).sqrt();
    let rows = (n as f64 / (w / 2.64 - 1.0)).ceil() + 2.0;
    (Vec2::ZERO, Vec2::new(w, rows * 2.64 * 0.87 + 3.0))
}

/// The dense packing of n discs side by side `k` times (a wider box): a
/// dense packing of `k n` discs without settling them, and its box.
pub fn dense_tiled(n: usize, k: usize) -> (Vec<DiscRow>, Vec2, Vec2) {
    let (lo, hi) = bounds(n);
    let w = hi.x - lo.x;
    let one = dense(n);
    let rows = (0..k)
        .flat_map(|t| {
            one.iter().map(move |r| DiscRow {
                pos: Vec2::new(r.pos.x + t as f64 * w, r.pos.y),
                ..r.clone()
            })
        })
        .collect();
    (rows, lo, Vec2::new(lo.x + k as f64 * w, hi.y))
}

/// n discs on a jittered hexagonal lattice filling the box from the floor.
pub fn loose(n: usize) -> Vec<DiscRow> {
    let (lo, hi) = bounds(n);
    lattice_packing(Lattice::Hex, lo, hi, (0.8, 1.2), Some(n), 0.1, 1.0, 42).expect("fits")
}

/// Where the dense packing of n discs is cached.
pub fn dense_path(n: usize) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("target/dem-bench-cache")
        .join(format!("dense_{n}.csv"))
}

/// The dense settled packing of n discs (made once, then read from the cache).
pub fn dense(n: usize) -> Vec<DiscRow> {
    let path = dense_path(n);
    if let Ok(text) = std::fs::read_to_string(&path)
        && let Ok(rows) = discs_from_csv(&text)
        && rows.len() == n
    {
        return rows;
    }
    eprintln!(
        "settling {n} discs once for the dense packing (cached in {})",
        path.display()
    );
    let (lo, hi) = bounds(n);
    // deposit under 10 g (faster), then relax under g
    let g10 = Vec2::new(0.0, -98.1);
    let rows = settle_in_box(&loose(n), lo, hi, law(), 1.0, 1.0, g10, 6_000, &mut |_| {
        true
    })
    .expect("settles");
    let g = Vec2::new(0.0, -9.81);
    let rows =
        settle_in_box(&rows, lo, hi, law(), 1.0, 1.0, g, 10_000, &mut |_| true).expect("settles");
    if let Some(dir) = path.parent() {
        std::fs::create_dir_all(dir).ok();
    }
    let mut s = String::from("x,y,r\n");
    for r in &rows {
        s.push_str(&format!("{:e},{:e},{:e}\n", r.pos.x, r.pos.y, r.r));
    }
    std::fs::write(&path, s).ok();
    rows
}

/// The benchmark assembly: normal dashpot ζ = 0.2, Δt = 0.15 × critical,
/// gravity, four fixed walls; disc forces not kept (as `efgdem run`
/// between frames). `DEM_BENCH_ROLLING=μ_r` adds rolling resistance
/// (rolling dashpot η_r = 0.3).
pub fn assembly(rows: &[DiscRow], n: usize) -> Granular {
    let (lo, hi) = bounds(n);
    assembly_in(rows, lo, hi)
}

/// [`assembly`] in the box `[lo, hi]`.
pub fn assembly_in(rows: &[DiscRow], lo: Vec2, hi: Vec2) -> Granular {
    let mut p = Particles::with_capacity(rows.len());
    for r in rows {
        p.push(r.pos, r.r, 1.0, 1.0, 0);
    }
    let c = [lo, Vec2::new(hi.x, lo.y), hi, Vec2::new(lo.x, hi.y)];
    let walls = (0..4)
        .map(|k| Wall::new("box", c[k], c[(k + 1) % 4], WallMotion::Fixed))
        .collect();
    let mut l = law();
    l.zeta_n = 0.2;
    if let Some(mu_r) = std::env::var("DEM_BENCH_ROLLING")
        .ok()
        .and_then(|s| s.parse::<f64>().ok())
    {
        l.mu_roll = mu_r;
        l.roll_damping = 0.3;
    }
    let mut g = Granular::new(p, vec![l], walls, 1.0);
    g.dt = 0.15 * g.critical_dt();
    g.gravity = Vec2::new(0.0, -9.81);
    g.store_forces = false;
    g
}
