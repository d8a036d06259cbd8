//! The sub-cycled scheme (`substeps` > 1): a body step every n DEM steps,
//! the contact boundary on the path predicted under the last body step's
//! loads. Energy against the exact implicit step on a stiff footing driven
//! into an undamped, frictionless bed (the account's only dissipation is
//! numerical), the refusal of a body too soft for it, and the corner of a
//! closed contact chain in the exact scheme.

use efgdem::coupling::CouplingError;
use efgdem::coupling::energy::WorkMeter;
use efgdem::coupling::scheme::{
    COMPLIANT_DAMPED_OMEGA_H, COMPLIANT_MAX_OMEGA_H, COMPLIANT_UNDAMPED_OMEGA_H, Scheme,
};
use efgdem::model::Model;
use efgdem::model::ModelError;
use efgdem::scenario::parse;

/// `examples/hex_footing.toml`: a hexagonal bed of 446 discs (r = 5 mm,
/// k_n = 10⁷ N/m, no damping, no friction) under gravity, and an EFG
/// footing 0.2 × 0.04 m (41 × 9 nodes, γ = ½, β = ¼, all edges in
/// contact) 0.5 mm above it whose top edge is
/// driven down at 5 cm/s: it meets the bed at 0.01 s and pushes ~25 discs
/// into it (peak ≈ 28 kN/m at 0.04 s), then the bed throws them off.
const FOOTING: &str = include_str!("../examples/hex_footing.toml");

/// [`scenario`] with the predicted scheme named (`coupling = "predicted"`).
fn predicted(substeps: usize, modulus: &str, end: f64) -> String {
    scenario(substeps, modulus, end).replace(
        &format!("substeps = {substeps}\n"),
        &format!("substeps = {substeps}\ncoupling = \"predicted\"\n"),
    )
}

fn scenario(substeps: usize, modulus: &str, end: f64) -> String {
    let src = FOOTING
        .replace(
            "end_time = 0.05\n",
            &format!("end_time = {end}\nsubsteps = {substeps}\n"),
        )
        .replace("E = 2.0e9", &format!("E = {modulus}"));
    assert!(src.contains(&format!("substeps = {substeps}\n")) && src.contains(modulus));
    src
}

/// Largest |E_diss| and largest W_ext over the run, sampled at the body
/// steps (in between, the discs are ahead of the bodies' state), and the
/// mean vertical force of the discs on the footing over 0.015–0.045 s.
fn energy_error(src: &str) -> (f64, f64, f64) {
    let mut m: Model = parse(src, "footing.toml").unwrap().build().unwrap();
    energy_error_of(&mut m)
}

/// [`energy_error`] of a model built.
fn energy_error_of(m: &mut Model) -> (f64, f64, f64) {
    let substeps = m.coupled().unwrap().substeps;
    let mut meter = WorkMeter::new(m.coupled().unwrap());
    let (mut diss, mut work, mut push, mut n) = (0.0f64, 0.0f64, 0.0, 0);
    for step in 1..=m.steps {
        m.step().unwrap();
        let c = m.coupled().unwrap();
        meter.after_step(&c.granular);
        if (0.015..0.045).contains(&c.granular.time) {
            push -= c.contacts.iter().map(|q| q.force.y).sum::<f64>();
            n += 1;
        }
        if step % substeps == 0 {
            let e = meter.account(c);
            diss = diss.max(e.diss.abs());
            work = work.max(e.w_ext.abs());
        }
    }
    (diss, work, push / n.max(1) as f64)
}

/// Through the impact and the push (to 0.05 s): the exact step keeps
/// |E_diss| at 0.1 % of the work (the DEM's own central-difference error),
/// 50 substeps at 0.2 %. Without the end load extrapolated from the step's
/// average (the average put at the end: a lag of half a body step) the
/// error was 1.3 %, so the bound 0.5 % catches it. The footing's mean
/// reaction over the push agrees with the exact step’s to 0.06 % (the bed's
/// own chaos makes single instants differ more; 2 % would catch a lag or
/// a lost share of the loads).
#[test]
fn subcycled_footing_keeps_the_energy_of_the_exact_step() {
    let (d1, w1, f1) = energy_error(&scenario(1, "30.0e9", 0.05));
    let (d50, w50, f50) = energy_error(&scenario(50, "30.0e9", 0.05));
    assert!(w1 > 20.0 && w50 > 20.0, "the drive works: {w1} {w50}");
    assert!(d1 < 2e-3 * w1, "exact: {d1} of {w1}");
    assert!(d50 < 5e-3 * w50, "50 substeps: {d50} of {w50}");
    assert!(f1 > 1.5e4, "the bed pushes back: {f1}");
    assert!((f50 - f1).abs() < 0.02 * f1, "reaction {f50} vs {f1}");
}

/// A body soft against the contacts over a body step (E = 0.1 GPa: the
/// predicted scheme's collective gain 0.3 at 10 substeps): with `substeps
/// = 10` alone the build gives it the compliant scheme, which is stable
/// whatever the gain; named `coupling = "predicted"` it is built with a
/// warning that gives the gain and the rule.
#[test]
fn a_body_too_soft_for_the_predicted_scheme_gets_the_compliant_one() {
    let m: Model = parse(&scenario(10, "1.0e8", 0.001), "soft.toml")
        .unwrap()
        .build()
        .unwrap();
    let c = m.coupled().unwrap().choice.clone().unwrap();
    assert_eq!(c.scheme, Scheme::Compliant, "{}", c.why);
    assert_eq!(c.substeps, 10);
    assert!(c.why.contains("not safe"), "{}", c.why);
    let m: Model = parse(&predicted(10, "1.0e8", 0.001), "soft.toml")
        .unwrap()
        .build()
        .unwrap();
    let c = m.coupled().unwrap().choice.clone().unwrap();
    assert_eq!(c.scheme, Scheme::Predicted);
    let w = c.warning.unwrap();
    assert!(w.contains("collective gain Γ = 0.3"), "{w}");
}

/// The exact scheme on a softer footing (E = 3 GPa): at 0.0386 s a disc
/// beside the bottom-left corner — both ends of the closed contact chain —
/// was taken as inside the body (the corner's normal from the bottom edge
/// alone): an overlap of 2r, 10⁵ N for one step, 7.3 J created. Now
/// |E_diss| stays at the DEM's level.
#[test]
fn closed_chain_corner_creates_no_energy() {
    let (d, w, _) = energy_error(&scenario(1, "3.0e9", 0.04));
    assert!(w > 20.0, "{w}");
    assert!(d < 2e-3 * w, "{d} of {w}");
}

/// The scheme's own account of the energy it creates (what the bodies
/// received less what the discs did on the paths) against the independent
/// energy account's `E_diss` (work less stored energy): on the 3 GPa
/// footing at 10 substeps the predicted scheme (named: its gain 0.023 is
/// above the automatic choice's limit at this body step) creates ≈ 0.5 % of the exchanged work
/// (under the 2 % at which a run stops) and `−E_diss` shows the same.
#[test]
fn subcycling_energy_is_what_the_account_misses() {
    let src = predicted(10, "3.0e9", 0.06);
    let mut m: Model = parse(&src, "footing.toml").unwrap().build().unwrap();
    let mut meter = WorkMeter::new(m.coupled().unwrap());
    for _ in 0..m.steps {
        m.step().unwrap();
        meter.after_step(&m.coupled().unwrap().granular);
    }
    let c = m.coupled().unwrap();
    let (created, exchanged) = c.subcycling_energy();
    let diss = meter.account(c).diss;
    assert!(
        created > 0.002 * exchanged && created < 0.01 * exchanged,
        "{created} of {exchanged}"
    );
    // the DEM's own error is ≈ 0.03 J here (the exact step's |E_diss|)
    assert!(
        (created + diss).abs() < 0.25 * created + 0.03,
        "created {created}, E_diss {diss}"
    );
}

/// A body soft enough to go unstable at 10 substeps of the predicted
/// scheme (E = 2 GPa, named against the warning; run on, it creates 5 % of
/// the work) is stopped by `efgdem run` with the energy created (exit
/// code 3, an instability) before the end, its history kept up to there
/// and its summary written.
#[test]
fn an_unstable_subcycled_run_stops() {
    let dir = std::env::temp_dir().join(format!("efgdem-subcycled-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("soft.toml");
    std::fs::write(
        &file,
        predicted(10, "2.0e9", 0.08) + "[output]\nevery = 100\n",
    )
    .unwrap();
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_efgdem"))
        .args(["run", file.to_str().unwrap(), "-q", "--overwrite", "-o"])
        .arg(dir.join("out"))
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(3), "{err}");
    assert!(
        err.contains("body `footing`: the sub-cycled scheme (predicted) created"),
        "{err}"
    );
    let history = std::fs::read_to_string(dir.join("out/history.csv")).unwrap();
    let last: f64 = history
        .lines()
        .last()
        .unwrap()
        .split(',')
        .nth(1)
        .unwrap()
        .parse()
        .unwrap();
    assert!((0.015..0.075).contains(&last), "stopped at t = {last}");
    // nothing lost: the summary says how it ended
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("out/summary.json")).unwrap())
            .unwrap();
    assert_eq!(summary["status"], "unstable");
    let failure = summary["failure"].as_str().unwrap();
    assert!(
        failure.contains("sub-cycled scheme (predicted) created"),
        "{failure}"
    );
    std::fs::remove_dir_all(&dir).ok();
}

/// `efgdem check` reports the scheme chosen for `substeps = 50` and each
/// body's collective gain.
#[test]
fn check_reports_the_subcycling_gain() {
    let dir = std::env::temp_dir().join(format!("efgdem-subcycled-check-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("stiff.toml");
    std::fs::write(&file, scenario(50, "30.0e9", 0.001)).unwrap();
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_efgdem"))
        .args(["check", file.to_str().unwrap()])
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{text}");
    assert!(
        text.contains("coupled scheme: predicted with 50 DEM step(s) per body step (chosen)")
            && text.contains(
                "predicted scheme at 50 substeps (ω_c h = 3.47): collective gain `footing` 0.0062"
            ),
        "{text}"
    );
    // docs/howto/choose-scheme-and-time-step.md shows this output
    let page = std::fs::read_to_string(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("docs/howto/choose-scheme-and-time-step.md"),
    )
    .unwrap();
    let shown = page
        .split("```text\n")
        .find(|b| b.starts_with("coupled scheme: predicted with 50"))
        .and_then(|b| b.split("```").next())
        .expect("the page shows the output of `check`");
    for line in shown.lines() {
        assert!(
            text.contains(line.trim()),
            "the page shows {line:?}, `check` prints:\n{text}"
        );
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// The same unstable run driven through the Rust API, `Model::step`: the
/// energy guard is in the model, so the step returns the typed error (a
/// numerical failure, exit code 3 from the CLI) before the end.
#[test]
fn the_energy_guard_stops_model_step() {
    let mut m: Model = parse(&predicted(10, "2.0e9", 0.08), "soft.toml")
        .unwrap()
        .build()
        .unwrap();
    let steps = m.steps;
    let err = loop {
        match m.step() {
            Ok(()) => assert!(m.step < steps, "the unstable run finished"),
            Err(e) => break e,
        }
    };
    assert!(err.is_numerical(), "{err}");
    let ModelError::Coupling(CouplingError::Subcycling {
        body,
        scheme,
        created,
        exchanged,
        ..
    }) = &err
    else {
        panic!("{err}")
    };
    assert_eq!((body.as_str(), *scheme), ("footing", "predicted"));
    assert!(*created > 0.02 * exchanged, "{created} of {exchanged}");
    let t = m.time();
    assert!((0.015..0.075).contains(&t), "stopped at t = {t}");
}

/// A contact solve that cannot converge (`contact_iterations = 1`: the
/// first contact changes the regimes) stops `efgdem run` with exit code 3
/// and a message naming the body and the step.
#[test]
fn a_contact_solve_that_does_not_converge_stops_the_run() {
    let dir = std::env::temp_dir().join(format!("efgdem-newton-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("cap.toml");
    let src = scenario(1, "30.0e9", 0.02)
        .replace("substeps = 1\n", "substeps = 1\ncontact_iterations = 1\n");
    std::fs::write(&file, src).unwrap();
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_efgdem"))
        .args(["run", file.to_str().unwrap(), "-q", "--overwrite", "-o"])
        .arg(dir.join("out"))
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(3), "{err}");
    assert!(
        err.contains("body `footing`: the contact solve did not converge at step ")
            && err.contains("after 1 Newton iterations"),
        "{err}"
    );
    std::fs::remove_dir_all(&dir).ok();
}

/// [`scenario`] without `substeps` (the automatic choice) on a bed 1.2 m
/// wide (1 200 discs: above the size where the choice keeps the exact
/// step), or with `coupling = "exact"`.
fn wide(modulus: &str, exact: bool) -> String {
    let src = scenario(1, modulus, 0.05)
        .replace(
            "substeps = 1\n",
            if exact { "coupling = \"exact\"\n" } else { "" },
        )
        .replace("[0.5, 0.085]", "[1.2, 0.085]")
        .replace(
            "from = [0.5, 0.0]\nto = [0.5, 0.3]",
            "from = [1.2, 0.0]\nto = [1.2, 0.3]",
        );
    assert!(src.contains("[1.2, 0.3]"));
    src
}

/// The automatic scheme on the soft (E = 0.1 GPa), a middling (5 GPa)
/// and the stiff (30 GPa) footing, pushed into the wide bed: it sub-cycles
/// all three (the soft one with the compliant scheme at the contacts'
/// limit, the middling one with the compliant scheme at its collective
/// mode's limit `ω_b h ≤ 2`, the stiff one with the predicted scheme), its
/// own account of the energy it created stays within 1 % of the work the
/// footing exchanged, the whole system's |E_diss| (the only dissipation
/// is numerical) within 1 % of the work, and the footing's mean reaction
/// over the push within 1 % of the exact step's.
#[test]
fn the_automatic_scheme_keeps_the_energy_and_the_reaction_of_the_exact_step() {
    for (modulus, scheme) in [
        ("1.0e8", Scheme::Compliant),
        ("5.0e9", Scheme::Compliant),
        ("30.0e9", Scheme::Predicted),
    ] {
        let src = wide(modulus, false);
        let m: Model = parse(&src, "wide.toml").unwrap().build().unwrap();
        let choice = m.coupled().unwrap().choice.clone().unwrap();
        assert!(
            choice.automatic && choice.scheme == scheme,
            "{}",
            choice.why
        );
        if scheme == Scheme::Compliant {
            // the longest body step that resolves both the undamped
            // contacts' period (ω_c h ≤ 1.75) and the body's collective
            // mode (ω_b h ≤ 2)
            let by_contacts = (COMPLIANT_UNDAMPED_OMEGA_H / choice.omega_dt).floor();
            let by_body = (COMPLIANT_MAX_OMEGA_H / choice.body_omega_dt).floor();
            assert_eq!(choice.substeps, by_contacts.min(by_body) as usize);
        }
        drop(m);
        let mut m: Model = parse(&src, "wide.toml").unwrap().build().unwrap();
        let (d, w, f) = energy_error_of(&mut m);
        let (created, exchanged) = m.coupled().unwrap().subcycling_energy();
        let (d1, w1, f1) = energy_error(&wide(modulus, true));
        println!(
            "E = {modulus}: {} × {}: created {created:.3e} of {exchanged:.3e} exchanged; |E_diss| {d:.3e} of {w:.3e} (exact {d1:.3e} of {w1:.3e}); reaction {f:.1} vs exact {f1:.1} N/m",
            choice.scheme.name(),
            choice.substeps
        );
        assert!(
            w > 5.0 && exchanged > 1.0,
            "the drive works: {w} {exchanged}"
        );
        assert!(
            created.abs() <= 0.01 * exchanged,
            "{created} of {exchanged}"
        );
        assert!(d <= 0.01 * w, "|E_diss| {d} of {w}");
        assert!((f - f1).abs() <= 0.01 * f1.abs(), "reaction {f} vs {f1}");
    }
}

/// `src` (the hex bed) with the discs' `damping` table `{ damping }`.
fn with_damping(src: String, damping: &str) -> String {
    let src = src.replace(
        "radius = 0.005 }\n",
        &format!("radius = 0.005 }}\ndamping = {{ {damping} }}\n"),
    );
    assert!(src.contains(damping));
    src
}

/// On a bed whose contacts carry a normal dashpot (ζ = 0.05 of critical,
/// the least the choice counts as damped, frictionless; and ζ = 0.2 with
/// friction 0.5, as `examples/soft_footing.toml`), the automatic scheme
/// takes the compliant body steps of a footing soft enough (E = 20 MPa)
/// that its own collective mode does not bound them up to `ω_c h` = 4
/// (1.75 on undamped contacts): its own account of the energy it created
/// stays within 1 % of the work the footing exchanged, and the mean
/// reaction over the push within 1 % of the exact step's.
#[test]
fn the_automatic_scheme_takes_longer_body_steps_on_damped_contacts() {
    for (zeta, friction) in [("0.05", "0.0"), ("0.2", "0.5")] {
        let damped = |exact| {
            let dashpot = format!("kind = \"critical-ratio\", zeta = {zeta}");
            let src = with_damping(wide("2.0e7", exact), &dashpot)
                .replace("friction = 0.0\n", &format!("friction = {friction}\n"));
            assert!(src.contains(&format!("friction = {friction}\n")));
            src
        };
        let mut m: Model = parse(&damped(false), "damped.toml")
            .unwrap()
            .build()
            .unwrap();
        let choice = m.coupled().unwrap().choice.clone().unwrap();
        assert!(
            choice.automatic && choice.scheme == Scheme::Compliant,
            "{}",
            choice.why
        );
        assert!(choice.body_omega_dt < choice.omega_dt, "{}", choice.why);
        assert_eq!(
            choice.substeps,
            (COMPLIANT_DAMPED_OMEGA_H / choice.omega_dt).floor() as usize,
            "{}",
            choice.why
        );
        assert!(choice.why.contains("damped at ζ = "), "{}", choice.why);
        let (_, _, f) = energy_error_of(&mut m);
        let (created, exchanged) = m.coupled().unwrap().subcycling_energy();
        let (_, _, f1) = energy_error(&damped(true));
        println!(
            "ζ = {zeta}, friction {friction}: compliant × {}: created {created:.3e} of {exchanged:.3e} exchanged; reaction {f:.1} vs exact {f1:.1} N/m",
            choice.substeps
        );
        assert!(exchanged > 1.0, "the drive works: {exchanged}");
        assert!(
            created.abs() <= 0.01 * exchanged,
            "{created} of {exchanged}"
        );
        assert!((f - f1).abs() <= 0.01 * f1.abs(), "reaction {f} vs {f1}");
    }
}

/// The dashpot the choice counts: `ζ_n` of a critical-ratio one, or
/// `β_n ω / 2` of a stiffness-proportional one at the heaviest disc's
/// `ω = √(k_n/m)` (here 6 931 rad/s: r = 5 mm, ρ = 2650, k_n = 10⁷), on
/// either side of the 5 % from which the contacts count as damped.
#[test]
fn the_choice_counts_the_contacts_dashpots() {
    let omega = (1.0e7f64 / (2650.0 * std::f64::consts::PI * 0.005 * 0.005)).sqrt();
    for (damping, zeta, damped) in [
        (
            "kind = \"critical-ratio\", zeta = 0.08".to_string(),
            0.08,
            true,
        ),
        (
            format!("kind = \"contact-viscous\", beta = {:e}", 0.2 / omega),
            0.1,
            true,
        ),
        (
            format!("kind = \"contact-viscous\", beta = {:e}", 0.06 / omega),
            0.03,
            false,
        ),
    ] {
        let src = with_damping(wide("2.0e7", false), &damping);
        let m: Model = parse(&src, "damped.toml").unwrap().build().unwrap();
        let c = m.coupled().unwrap();
        let got = efgdem::coupling::scheme::contact_zeta(c);
        assert!((got - zeta).abs() < 1e-12, "{damping}: ζ = {got}");
        let choice = c.choice.as_ref().unwrap();
        let bound = if damped { 4.0 } else { 1.75 };
        assert_eq!(
            choice.substeps,
            (bound / choice.omega_dt).floor() as usize,
            "{}",
            choice.why
        );
        assert!(
            choice.why.contains(&format!("ζ = {zeta:.3}")),
            "{}",
            choice.why
        );
    }
}

/// The unstable run of [`the_energy_guard_stops_model_step`] with its
/// scheme marked as chosen automatically: each time the guard catches it,
/// the model goes on with at most half the substeps (10 → 5 → 2 here,
/// each still creating energy on this soft body), and then with the exact
/// step, instead of failing. The run completes; the scheme creates
/// nothing after the last switch (the body's path account stays put) and
/// the energy account's error grows by no more than the exact step's own
/// (0.2 % of the work: twice what the exact step keeps on this bed from
/// the start); each switch is said once and recorded in the choice and
/// the state; a restart after the first switch and after the last
/// continues bitwise, while a state from before a switch is refused by
/// the switched model.
#[test]
fn an_automatic_scheme_that_creates_energy_falls_back_to_fewer_substeps() {
    let src = predicted(10, "2.0e9", 0.08);
    let build = || {
        let mut m: Model = parse(&src, "soft.toml").unwrap().build().unwrap();
        let c = m.coupled_mut().unwrap();
        c.choice.as_mut().unwrap().automatic = true;
        m
    };
    let mut m = build();
    let early = m.save_state();
    let mut meter = WorkMeter::new(m.coupled().unwrap());
    let mut at_switch = None;
    let mut notices = Vec::new();
    let mut switches = Vec::new();
    let (mut mid_first, mut mid) = (None, None);
    while m.step < m.steps {
        m.step().unwrap();
        notices.extend(m.take_notices());
        let c = m.coupled().unwrap();
        meter.after_step(&c.granular);
        if let Some(f) = &c.fallback
            && switches.last() != Some(&(f.substeps, f.to))
        {
            switches.push((f.substeps, f.to));
            if f.to == 1 {
                let e = meter.account(c);
                at_switch = Some((e.diss, c.bodies[0].path_energy().0, m.step));
            }
        }
        if switches.len() == 1 && mid_first.is_none() {
            mid_first = Some(m.save_state());
        }
        if at_switch.is_some_and(|(_, _, s)| m.step == s + 37) {
            mid = Some(m.save_state());
        }
    }
    assert_eq!(switches, [(10, 5), (5, 2), (2, 1)]);
    let c = m.coupled().unwrap();
    let f = c.fallback.clone().expect("the scheme fell back");
    assert_eq!(
        (f.from.as_str(), f.substeps, f.body.as_str()),
        ("predicted", 2, "footing")
    );
    assert!(f.time < 0.08, "switched at t = {}", f.time);
    assert!(f.created > 0.02 * f.exchanged);
    let choice = c.choice.as_ref().unwrap();
    assert_eq!((choice.scheme, choice.substeps), (Scheme::Exact, 1));
    assert_eq!(choice.fallback.as_ref(), Some(&f));
    assert_eq!(notices.len(), 3, "{notices:?}");
    assert!(
        notices[0].contains("the predicted scheme goes on with 5 substeps"),
        "{}",
        notices[0]
    );
    assert!(
        notices[2].contains("the exact step is taken from step"),
        "{}",
        notices[2]
    );
    let (diss0, created0, _) = at_switch.unwrap();
    assert_eq!(c.bodies[0].path_energy().0, created0);
    let e = meter.account(c);
    assert!(e.w_ext > 20.0, "the drive works: {}", e.w_ext);
    assert!(
        (e.diss - diss0).abs() < 2e-3 * e.w_ext,
        "after the switch: E_diss {diss0} -> {} of {}",
        e.diss,
        e.w_ext
    );
    // a restart after the first switch and after the last continues bitwise
    let end = m.save_state().to_bytes();
    for (when, state) in [("first", mid_first.unwrap()), ("last", mid.unwrap())] {
        let mut r = build();
        r.restore_state(&state).unwrap();
        while r.step < r.steps {
            r.step().unwrap();
        }
        assert!(
            r.save_state().to_bytes() == end,
            "restart after the {when} switch"
        );
    }
    // a state of the sub-cycled scheme does not fit the switched model
    let err = m.restore_state(&early).unwrap_err().to_string();
    assert!(err.contains("given up for shorter body steps"), "{err}");
}
