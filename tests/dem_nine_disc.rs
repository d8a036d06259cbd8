//! Cundall & Strack's nine-disc test with rigid plates (issue 3,
//! validation item 5) and the stability of the shear dashpot.

use efgdem::dem::Granular;
use efgdem::scenario;

const EX1: &str = include_str!("../examples/nine_disc_rigid_test1.toml");
const EX2: &str = include_str!("../examples/nine_disc_rigid_test2.toml");

/// The example scenario with its damping line and friction replaced.
fn assembly(src: &str, damping: &str, friction: f64) -> Granular {
    let src = src
        .lines()
        .map(|l| {
            if l.starts_with("damping =") {
                format!("damping = {damping}")
            } else if l.starts_with("friction =") {
                format!("friction = {friction}")
            } else {
                l.to_string()
            }
        })
        .collect::<Vec<_>>()
        .join("\n");
    let sc = scenario::parse(&src, "nine_disc.toml").expect("valid scenario");
    sc.build().expect("builds").into_granular().unwrap()
}

/// The middle row (discs 4, 5, 6) as a 1D chain: three masses, four
/// springs k_n (never tensile), the outer ends on the plates that move at
/// ±v for `n_move` cycles. Same central difference as the DEM. Returns
/// the force at C (springs 4–5) after each cycle 1..=150.
fn chain(v: f64, n_move: usize) -> Vec<f64> {
    let (k, r, dt) = (1.35e9, 50.0, 0.01525);
    let m = 1000.0 * std::f64::consts::PI * r * r;
    let mut x = [50.0, 150.0, 250.0];
    let mut u = [0.0; 3];
    let (mut xl, mut xr) = (0.0, 300.0);
    let spring = |d: f64| k * d.max(0.0);
    let mut out = Vec::new();
    for n in 0..150 {
        let f_l = spring(r - (x[0] - xl));
        let f_45 = spring(2.0 * r - (x[1] - x[0]));
        let f_56 = spring(2.0 * r - (x[2] - x[1]));
        let f_r = spring(r - (xr - x[2]));
        let f = [f_l - f_45, f_45 - f_56, f_56 - f_r];
        for i in 0..3 {
            u[i] += f[i] / m * dt;
            x[i] += u[i] * dt;
        }
        if n < n_move {
            xl += v * dt;
            xr -= v * dt;
        }
        out.push(spring(2.0 * r - (x[1] - x[0])));
    }
    out
}

fn check_chain(src: &str, v: f64, n_move: usize) {
    let mut g = assembly(src, "{ kind = \"none\" }", 0.0);
    let reference = chain(v, n_move);
    let fmax = reference.iter().copied().fold(0.0, f64::max);
    let mut worst = 0.0f64;
    for (c, &fr) in reference.iter().enumerate() {
        g.step();
        // slots can change when discs are renumbered: look them up each time
        let (f, _) = g.normal_force(g.slot(3), g.slot(4));
        let err = (f - fr).abs();
        worst = worst.max(err / fr.abs().max(1e-300));
        assert!(
            err <= 1e-6 * fr.abs() + 1e-12 * fmax,
            "cycle {}: force_C {f:e} vs chain {fr:e}",
            c + 1
        );
    }
    println!("v = {v}: force_C matches the chain, worst relative error {worst:.2e}");
}

#[test]
fn undamped_frictionless_middle_row_is_a_chain_test1() {
    check_chain(EX1, 0.12, 40);
}

#[test]
fn undamped_frictionless_middle_row_is_a_chain_test2() {
    check_chain(EX2, 0.04, 120);
}

/// Largest spin and kinetic energy over 150 cycles of Test 1.
fn spin_run(damping: &str) -> (f64, f64, bool) {
    let mut g = assembly(EX1, damping, 0.5);
    let mut wmax = 0.0f64;
    for _ in 0..150 {
        g.step();
        if !g.is_finite() {
            return (f64::INFINITY, f64::INFINITY, false);
        }
        wmax = g.particles.omega.iter().fold(wmax, |a, w| a.max(w.abs()));
    }
    let e = g.energies();
    (wmax, e.kinetic + e.rotational, true)
}

/// Normal dashpot β k_n (β = 0.1) is stable at Δt = 0.01525; adding a
/// shear dashpot β k_s is not: for a disc with I = m r²/2 the contact-point
/// tangential mass is m/3, so the dashpot's explicit stability limit
/// `c_s Δt Σ(1/m_eff) < 2` is exceeded (0.1·1.35e9·0.01525·16/7.85e6 ≈ 4.2
/// for the centre disc spinning against its four neighbours).
#[test]
fn shear_dashpot_is_unstable_at_this_step() {
    let (w_ok, e_ok, fin_ok) =
        spin_run("{ kind = \"contact-viscous\", beta = 0.1, beta_shear = 0.0 }");
    let (w_bad, e_bad, fin_bad) =
        spin_run("{ kind = \"contact-viscous\", beta = 0.1, beta_shear = 0.1 }");
    println!("normal dashpot only: max |ω| {w_ok:e}, final kinetic {e_ok:e} (finite {fin_ok})");
    println!("with shear dashpot:  max |ω| {w_bad:e}, final kinetic {e_bad:e} (finite {fin_bad})");
    assert!(fin_ok);
    // without the shear dashpot the spins stay at round-off and the motion
    // dies out; with it, round-off is amplified by ~|1 − 4.2| per step until
    // friction limits it, and the kinetic energy grows instead of decaying
    assert!(w_ok < 1e-9 && e_ok < 1e-6);
    assert!(
        w_bad > 1e6 * w_ok.max(1e-15),
        "expected the shear dashpot to blow up"
    );
    assert!(e_bad > 1e3, "kinetic energy {e_bad:e}");
}

/// Both shipped examples through the command line.
#[test]
fn shipped_examples_run_through_the_cli() {
    for (name, src_name) in [
        ("test1", "nine_disc_rigid_test1"),
        ("test2", "nine_disc_rigid_test2"),
    ] {
        let out = std::env::temp_dir().join(format!("efgdem-nine-{name}-{}", std::process::id()));
        let st = std::process::Command::new(env!("CARGO_BIN_EXE_efgdem"))
            .args(["run", &format!("examples/{src_name}.toml"), "-o"])
            .arg(&out)
            .arg("--quiet")
            .current_dir(env!("CARGO_MANIFEST_DIR"))
            .status()
            .expect("runs");
        assert!(st.success());
        let (h, rows) = efgdem::output::csv::read(&out.join("history.csv")).unwrap();
        assert_eq!(h, ["step", "t", "force_C", "force_C_total"]);
        // a row at step 0 and after each of the 150 cycles
        assert_eq!(rows.len(), 151);
        assert_eq!(rows[0][0], 0.0);
        assert_eq!(rows[150][0], 150.0);
        assert!(rows.iter().all(|r| r.iter().all(|v| v.is_finite())));
        let fc = rows[149][2];
        assert!(fc > 1e7 && fc < 1e8, "force_C at 150 = {fc:e}");
        // the dashpot has died out at the end: total ≈ elastic
        assert!((rows[149][3] - fc).abs() < 1e-3 * fc);
        assert!(out.join("summary.json").exists());
        assert!(out.join("discs.pvd").exists());
        assert!(out.join("frames/discs_0000150.vtp").exists());
        std::fs::remove_dir_all(&out).ok();
    }
}
