//! Rolling resistance (issue 13, §2) and the bitwise guarantee that
//! `rolling_friction = 0` (with `slip_normal = "elastic"` where a dashpot
//! makes the two Coulomb caps differ) is the code before issue 13.

use efgdem::scenario;

/// FNV-1a over the bits of the values.
#[derive(Clone, Copy)]
struct Hash(u64);

impl Hash {
    fn new() -> Self {
        Hash(0xcbf2_9ce4_8422_2325)
    }
    fn f(&mut self, x: f64) {
        for b in x.to_bits().to_le_bytes() {
            self.0 ^= u64::from(b);
            self.0 = self.0.wrapping_mul(0x0100_0000_01b3);
        }
    }
}

/// `src` with `extra` lines inserted after every `cohesion = ` line of a
/// `[[material]]`.
fn with_fields(src: &str, extra: &str) -> String {
    let mut out = String::new();
    for l in src.lines() {
        out.push_str(l);
        out.push('\n');
        if l.starts_with("cohesion =") && !extra.is_empty() {
            out.push_str(extra);
            out.push('\n');
        }
    }
    out
}

/// A loose random packing under gravity with a piston, two materials,
/// friction and cohesion; `damping` is the `[granular]` damping line.
fn packing(damping: &str) -> String {
    format!(
        r#"
[simulation]
dt = 1e-3
steps = 3000
gravity = [0.0, -9.81]

[[material]]
name = "grain"
density = 1.0
kn = 1.0e5
ks = 0.8e5
friction = 0.5
cohesion = 0.05

[[material]]
name = "steel"
density = 1.0
kn = 2.0e5
ks = 1.0e5
friction = 0.3
cohesion = 0.0

[granular]
material = "grain"
discs = {{ generate = "random", box = [[0.0, 0.0], [60.0, 50.0]], radius = [0.8, 1.2], count = 400, seed = 5, method = "loose" }}
damping = {damping}

[[wall]]
name = "floor"
from = [0.0, 0.0]
to = [60.0, 0.0]
material = "steel"

[[wall]]
name = "left"
from = [0.0, 0.0]
to = [0.0, 80.0]

[[wall]]
name = "right"
from = [60.0, 0.0]
to = [60.0, 80.0]
material = "steel"

[[wall]]
name = "piston"
from = [0.0, 51.0]
to = [60.0, 51.0]
velocity = [0.3, -4.0]
"#
    )
}

/// Hash of a granular run: disc states by scenario id every 50 steps,
/// and the wall forces.
fn dem_hash(src: &str) -> u64 {
    let sc = scenario::parse(src, "t.toml").expect("valid scenario");
    let model = sc.build().expect("builds");
    let steps = model.steps;
    let mut g = model.into_granular().expect("granular");
    let mut h = Hash::new();
    for s in 0..steps {
        g.step();
        if s % 50 == 49 || s + 1 == steps {
            let p = &g.particles;
            for id in 0..p.len() {
                let k = g.slot(id);
                for x in [p.pos[k].x, p.pos[k].y, p.vel[k].x, p.vel[k].y] {
                    h.f(x);
                }
                h.f(p.omega[k]);
                h.f(p.theta[k]);
            }
            for w in &g.walls {
                h.f(w.force.x);
                h.f(w.force.y);
            }
        }
    }
    h.0
}

/// Hash of a coupled run: disc states by id and the disc–body contact
/// forces, every step.
fn coupled_hash(src: &str) -> u64 {
    let sc = scenario::parse(src, "t.toml").expect("valid scenario");
    let model = sc.build().expect("builds");
    let steps = model.steps;
    let mut m = model.into_coupled().expect("coupled");
    let mut h = Hash::new();
    for _ in 0..steps {
        m.step().expect("steps");
        let g = &m.granular;
        let p = &g.particles;
        for id in 0..p.len() {
            let k = g.slot(id);
            for x in [p.pos[k].x, p.pos[k].y, p.vel[k].x, p.vel[k].y, p.omega[k]] {
                h.f(x);
            }
        }
        for c in &m.contacts {
            h.f(c.force.x);
            h.f(c.force.y);
            h.f(c.fs);
        }
    }
    h.0
}

/// Hashes of the same runs made with the code before issue 13 (commit
/// 31cfbc0, printed by this test then): a loose packing with dashpots,
/// the same with local damping only (no dashpot: both caps are `k_n δ`,
/// so the default needs no pin), the rigid nine-disc Test 1 and the EFG
/// nine-disc Test 1. The EFG one was pinned again at commit dd4831e, which
/// forms the contact solve's `S = Φ G Φᵀ` column by column instead of entry
/// by entry: another summation order, the same forces to round-off
/// (`tests/coupling_scale.rs` compares them with the direct solves); the
/// rolling-resistance pin below still reproduces that code bitwise. The
/// two packings were pinned again when the renumbering of the discs began
/// to order a neighbour grid cell's discs by id instead of by their
/// previous slot: the forces are summed in another order. With the cell
/// order switched back to the previous slot's (a one-line change of
/// `strip_order`), this code still gives the old hashes
/// (0xd72d4e5bb189b4c9, 0x91e0b02f06fa44ed): the order is the only change.
/// The EFG one was pinned a third time when the exact step's contact
/// solve began its Newton iterations at the body's free increment instead
/// of at zero (another iterate, the same solution to the solver's
/// tolerance): with the start set back to zero (a one-line change in
/// `coupling::implicit::Solver::solve`) this code still gives the previous
/// hash, 0x50b25af8a6a50ca7.
const GOLDEN: [(&str, u64); 4] = [
    ("packing, dashpots", 0xcc1218a967bdc7d2),
    ("packing, local damping", 0x907486789dd4bd99),
    ("nine discs rigid, test 1", 0xb9c022c14b04f4f1),
    ("nine discs EFG, test 1", 0xfa0f4d4c4c0d0fa9),
];

#[test]
fn rolling_friction_zero_is_bitwise_the_old_code() {
    // the pre-issue-13 code knew neither field: GOLDEN was made with PIN = ""
    const PIN: &str = "slip_normal = \"elastic\"\nrolling_friction = 0.0";
    let dashpots = "{ kind = \"critical-ratio\", zeta = 0.3, zeta_shear = 0.05 }";
    let local = "{ kind = \"local\", alpha = 0.3 }";
    let got = [
        dem_hash(&with_fields(&packing(dashpots), PIN)),
        dem_hash(&packing(local)),
        dem_hash(&with_fields(
            include_str!("../examples/nine_disc_rigid_test1.toml"),
            PIN,
        )),
        coupled_hash(&with_fields(
            include_str!("../examples/paper_nine_disc_test1.toml"),
            PIN,
        )),
    ];
    for ((name, _), got) in GOLDEN.iter().zip(got) {
        println!("(\"{name}\", {got:#018x}),");
    }
    for ((name, want), got) in GOLDEN.iter().zip(got) {
        assert_eq!(got, *want, "{name}: not bitwise the old result");
    }
    // the pin matters: with dashpots the default (total) cap is another run
    assert_ne!(dem_hash(&packing(dashpots)), GOLDEN[0].1);
}

// ---------------------------------------------------------------------
// Rolling resistance against analysis.

use efgdem::Vec2;
use efgdem::dem::Granular;
use efgdem::dem::contact::ContactLaw;
use efgdem::dem::particles::Particles;
use efgdem::dem::walls::{Wall, WallMotion};

#[allow(dead_code)]
mod common;

const R: f64 = 0.05;
const RHO: f64 = 2500.0;
const G: f64 = 9.81;
const KN: f64 = 1.0e6;

/// A disc of radius R on a horizontal wall (y = 0) under gravity `g`,
/// resting at its static overlap; rolling friction `mu_r`, friction 0.8
/// (it never slips here), normal dashpot ζ = 0.3.
fn disc_on_floor(mu_r: f64, eta_r: f64, g: Vec2, dt: f64) -> Granular {
    let mut p = Particles::default();
    let m = RHO * std::f64::consts::PI * R * R;
    p.push(Vec2::new(0.0, R + m * g.y / KN), R, RHO, 1.0, 0);
    let law = ContactLaw {
        kn: KN,
        ks: KN,
        mu: 0.8,
        zeta_n: 0.3,
        mu_roll: mu_r,
        roll_damping: eta_r,
        ..Default::default()
    };
    let floor = Wall::new(
        "floor",
        Vec2::new(-10.0, 0.0),
        Vec2::new(10.0, 0.0),
        WallMotion::Fixed,
    );
    let mut gr = Granular::new(p, vec![law], vec![floor], dt);
    gr.gravity = g;
    gr
}

/// Launched rolling (v0, ω0 = −v0/r) on a flat wall: the limiting moment
/// `μ_r r m g` takes the kinetic energy `¾ m v0²` (I = m r²/2) over the
/// rotation s/r, so the disc stops after `s = 3 v0²/(4 μ_r g)`.
#[test]
fn a_disc_rolling_on_a_wall_stops_after_three_quarters_v0_squared_over_mu_r_g() {
    for (mu_r, v0) in [(0.05, 0.5), (0.1, 1.0), (0.2, 1.0), (0.3, 2.0)] {
        let dt = 1e-4;
        let mut gr = disc_on_floor(mu_r, 0.3, Vec2::new(0.0, -G), dt);
        gr.particles.vel[0] = Vec2::new(v0, 0.0);
        gr.particles.omega[0] = -v0 / R;
        let x0 = gr.particles.pos[0].x;
        let mut stop = None;
        for _ in 0..200_000 {
            gr.step();
            if gr.particles.vel[0].x <= 0.0 {
                stop = Some(gr.particles.pos[0].x - x0);
                break;
            }
        }
        let s = stop.expect("the disc stops");
        let theory = 3.0 * v0 * v0 / (4.0 * mu_r * G);
        let err = (s - theory) / theory;
        println!(
            "μ_r = {mu_r}, v0 = {v0}: stops after {s:.5} m, theory {theory:.5} m, error {:+.3e} ({:.0} steps)",
            err, gr.step
        );
        assert!(err.abs() < 0.01, "μ_r = {mu_r}: {s} vs {theory}");
        // and stays (the rolling spring only rocks it back elastically)
        let x_stop = gr.particles.pos[0].x;
        for _ in 0..5000 {
            gr.step();
        }
        // the spring's elastic range is ±M_lim/k_r: rocking back from +M_lim
        // it turns the disc by at most 2 M_lim/k_r
        let back = (gr.particles.pos[0].x - x_stop).abs();
        let elastic = 2.0 * mu_r * R * gr.particles.mass[0] * G / (KN * R * R) * R;
        println!("   then moves {back:.2e} m (elastic range {elastic:.2e} m)");
        assert!(back <= 1.01 * elastic, "{back} vs {elastic}");
    }
}

/// On a slope θ (gravity tilted): the limit `μ_r r m g cos θ` holds the
/// gravity moment `m g sin θ r` while tan θ < μ_r; above, the disc rolls
/// down with `a = ⅔ g (sin θ − μ_r cos θ)`.
#[test]
fn a_disc_on_an_incline_stays_below_tan_theta_mu_r_and_rolls_above() {
    let mu_r = 0.2;
    for (tan, rolls) in [(0.15, false), (0.19, false), (0.21, true), (0.3, true)] {
        let th = f64::atan(tan);
        let g = Vec2::new(G * th.sin(), -G * th.cos());
        let dt = 1e-4;
        let mut gr = disc_on_floor(mu_r, 0.5, g, dt);
        // a shear dashpot settles the start-up oscillation of the shear
        // spring (the rolling dashpot is off at the limit)
        gr.materials[0].zeta_s = 0.3;
        gr.update_laws();
        // settle the start-up transient, then measure over [0.5, 1.0] s
        let mut x = [0.0; 3];
        let mut v = [0.0; 3];
        for (k, n) in [5000, 7500, 10000].into_iter().enumerate() {
            while gr.step < n {
                gr.step();
            }
            x[k] = gr.particles.pos[0].x;
            v[k] = gr.particles.vel[0].x;
        }
        if rolls {
            let a = (v[2] - v[0]) / 0.5;
            let theory = 2.0 / 3.0 * G * (th.sin() - mu_r * th.cos());
            let err = (a - theory) / theory;
            println!("tan θ = {tan}: rolls, a = {a:.5} vs {theory:.5} (error {err:+.2e})");
            assert!(err.abs() < 0.01);
            // rolling without slip: v = −ω r
            let w = gr.particles.omega[0];
            assert!((v[2] + w * R).abs() < 1e-3 * v[2]);
        } else {
            println!(
                "tan θ = {tan}: stays, x moved {:.2e} m in [0.5, 1] s, |v| = {:.2e}",
                x[2] - x[0],
                v[2].abs()
            );
            assert!((x[2] - x[0]).abs() < 1e-9 && v[2].abs() < 1e-8);
        }
    }
}

/// Energy: while the disc rolls at the limit, what it loses equals the
/// work of the limiting moment over the plastic rotation,
/// `E(0) − E(t) = μ_r r m g (|θ(t) − θ(0)| − M_lim/k_r)` (E with the
/// springs' energy, the rolling spring's `M²/(2k_r)` included; the spring
/// took the rest of the rotation elastically). No rolling dashpot, shear
/// sticking, no bounce: nothing else dissipates.
#[test]
fn energy_dissipated_by_the_rolling_limit_is_the_work_of_the_limiting_moment() {
    let (mu_r, v0) = (0.1, 1.0);
    for dt in [1e-4, 1e-5] {
        let mut gr = disc_on_floor(mu_r, 0.0, Vec2::new(0.0, -G), dt);
        gr.particles.vel[0] = Vec2::new(v0, 0.0);
        gr.particles.omega[0] = -v0 / R;
        // the contact list exists before the first step: E(0) has the
        // static overlap's spring energy
        gr.prepare_contacts();
        let e0 = gr.energies().total();
        let th0 = gr.particles.theta[0];
        let m_lim = mu_r * R * gr.particles.mass[0] * G;
        let kr = KN * R * R;
        // to t = 1 s: still rolling (it stops at 1.53 s); energies with the
        // synchronous velocities at t (mean of the half steps around it)
        let n = (1.0 / dt).round() as usize;
        let mut before = gr.clone();
        for _ in 0..n {
            before.clone_from(&gr);
            gr.step();
        }
        let p = &gr.particles;
        let e = before
            .energies_with(
                &[(before.particles.vel[0] + p.vel[0]) * 0.5],
                &[0.5 * (before.particles.omega[0] + p.omega[0])],
            )
            .total();
        let lost = e0 - e;
        let work = m_lim * ((before.particles.theta[0] - th0).abs() - m_lim / kr);
        let rel = (lost - work) / work;
        println!(
            "dt = {dt:e}: energy lost {lost:.8e} J, work of the limiting moment {work:.8e} J (rel {rel:+.2e})"
        );
        assert!(rel.abs() < 3e-4);
    }
}

/// Disc–disc sign convention and rolling radius: two discs held in place
/// (centres fixed, spins free), frictionless so that only the rolling
/// moment couples them. The moments are equal and opposite (`M` on i,
/// `−M` on j, from the relative rotation ω_i − ω_j), so `I_i ω_i + I_j ω_j`
/// is conserved, and at the limit `μ_r r̄ F_n` (r̄ = r_i r_j/(r_i + r_j))
/// the relative spin stops after `t = ω₀ / (M_lim (1/I_i + 1/I_j))`. Then
/// the spring rocks them elastically: `|ω_i − ω_j| ≤ M_lim/√(k_r I_eff)`,
/// `I_eff = (1/I_i + 1/I_j)⁻¹`, `k_r = k_s r̄²`.
#[test]
fn two_discs_share_their_spin_through_equal_and_opposite_rolling_moments() {
    use efgdem::dem::particles::{FIX_X, FIX_Y};
    let (r1, r2, kn, mu_r, w0) = (0.05, 0.08, 1e6, 0.2, 30.0);
    let delta = 1e-4;
    let mut p = Particles::default();
    p.push(Vec2::new(0.0, 0.0), r1, RHO, 1.0, 0);
    p.push(Vec2::new(r1 + r2 - delta, 0.0), r2, RHO, 1.0, 0);
    p.fixity = vec![FIX_X | FIX_Y; 2];
    p.omega[0] = w0;
    let (i1, i2) = (p.inertia[0], p.inertia[1]);
    let law = ContactLaw {
        kn,
        ks: kn,
        mu: 0.0,
        mu_roll: mu_r,
        ..Default::default()
    };
    let dt = 1e-5;
    let mut gr = Granular::new(p, vec![law], vec![], dt);
    let rbar = r1 * r2 / (r1 + r2);
    let m_lim = mu_r * rbar * kn * delta;
    let t_stop = w0 / (m_lim * (1.0 / i1 + 1.0 / i2));
    let w_final = i1 * w0 / (i1 + i2);
    let rock = m_lim / (law.roll_kr(rbar) / (1.0 / i1 + 1.0 / i2)).sqrt();
    let l0 = i1 * w0;
    let mut t_rel = None;
    let mut worst_l = 0.0f64;
    let mut rel_max = 0.0f64;
    let mut mean = (0.0, 0);
    while gr.time < 2.0 * t_stop {
        gr.step();
        let (a, b) = (gr.slot(0), gr.slot(1));
        let (wa, wb) = (gr.particles.omega[a], gr.particles.omega[b]);
        worst_l = worst_l.max((i1 * wa + i2 * wb - l0).abs() / l0);
        if t_rel.is_none() && wa <= wb {
            t_rel = Some(gr.time);
        }
        if t_rel.is_some() {
            rel_max = rel_max.max((wa - wb).abs());
            mean = (mean.0 + wa, mean.1 + 1);
        }
    }
    let t_rel = t_rel.expect("the spins meet");
    let mean = mean.0 / mean.1 as f64;
    println!(
        "relative spin stops at t = {t_rel:.6e} (theory {t_stop:.6e}); then mean spin {mean:.6} (theory {w_final:.6}), rocking |ω_i − ω_j| ≤ {rel_max:.4e} (elastic bound {rock:.4e}); angular momentum drift {worst_l:.1e}"
    );
    assert!(worst_l < 1e-10);
    assert!(((t_rel - t_stop) / t_stop).abs() < 1e-4);
    assert!(rel_max <= 1.001 * rock && rel_max > 0.9 * rock);
    assert!((mean - w_final).abs() < 2e-3 * w_final);
}

/// Rolling resistance keeps the sweep's guarantee: 1 and 2 threads give
/// bitwise the same run (cross-block pairs, renumbering, two materials,
/// walls, rolling dashpot).
#[test]
fn rolling_resistance_is_bitwise_thread_independent() {
    let src = packing("{ kind = \"critical-ratio\", zeta = 0.3 }")
        .replace("count = 400", "count = 900")
        .replace("[60.0, 50.0]", "[120.0, 50.0]")
        .replace("to = [60.0, 0.0]", "to = [120.0, 0.0]")
        .replace(
            "from = [60.0, 0.0]\nto = [60.0, 80.0]",
            "from = [120.0, 0.0]\nto = [120.0, 80.0]",
        )
        .replace("to = [60.0, 51.0]", "to = [120.0, 51.0]")
        .replace("steps = 3000", "steps = 1500");
    let src = with_fields(
        &src,
        "rolling_friction = 0.3\nrolling_damping = 0.3\nrolling_stiffness = 0.5",
    );
    let run = |threads: usize| common::on_threads(threads, || dem_hash(&src));
    let (a, b) = (run(1), run(2));
    println!("1 thread {a:#018x}, 2 threads {b:#018x}");
    assert_eq!(a, b);
    // and rolling resistance changed the run
    let off = with_fields(
        &src.replace("rolling_friction = 0.3", "rolling_friction = 0.0"),
        "",
    );
    assert_ne!(dem_hash(&off), a);
}
