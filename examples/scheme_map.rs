//! The measured map behind the automatic choice of the coupled scheme
//! (docs/howto/choose-scheme-and-time-step.md): an EFG footing driven at
//! 5 cm/s into a hexagonal bed of 446 discs (r = 5 mm, k_n = k_s = 10⁷
//! N/m; undamped and frictionless unless asked: the energy account's only
//! dissipation is then numerical), for several Young's moduli, each
//! scheme and substep count forced (past the build's safety rules). Per
//! run: the predicted scheme's collective gain Γ and ω_c h at that body
//! step, the largest
//! |E_diss| over the work at the body steps (the whole coupled system's
//! energy error), what the sub-cycled scheme's own account says it created
//! against the work it exchanged, and the footing's mean reaction over the
//! push (0.015–0.045 s) against the exact step's.
//!
//!     cargo run --release --example scheme_map -- [E,...] [n,...] [schemes] [ζ] [friction]
//!     cargo run --release --example scheme_map -- 1e8,1e9,2e9,3e9,1e10 5,10,20,50 predicted,compliant
//!     cargo run --release --example scheme_map -- 1e8,5e8,1e9,2e9,1e10 29,36,43,50,58 compliant 0.05 0.5
//!
//! `ζ`: a normal dashpot at that fraction of critical on every contact
//! (`damping = { kind = "critical-ratio" }`; the column of |E_diss| then
//! holds what it dissipates); `friction`: the discs' friction coefficient.

use efgdem::coupling::energy::WorkMeter;
use efgdem::coupling::scheme::{self, Choice, Scheme};
use efgdem::model::Model;
use efgdem::scenario::parse;

/// `examples/hex_footing.toml`, with the exact step named (each run
/// forces its scheme after the build).
const FOOTING: &str = include_str!("hex_footing.toml");

/// One run: (|E_diss|/W at body steps, created/exchanged, mean reaction,
/// Γ, ω_c h), or the error that stopped it.
fn run(
    e: f64,
    (zeta, mu): (f64, f64),
    scheme: Scheme,
    n: usize,
) -> Result<(f64, f64, f64, f64, f64), String> {
    let mut src = FOOTING.replace("E = 2.0e9", &format!("E = {e:e}")).replace(
        "end_time = 0.05\n",
        "end_time = 0.05\ncoupling = \"exact\"\n",
    );
    src = src.replace("friction = 0.0\n", &format!("friction = {mu}\n"));
    if zeta > 0.0 {
        src = src.replace(
            "radius = 0.005 }\n",
            &format!(
                "radius = 0.005 }}\ndamping = {{ kind = \"critical-ratio\", zeta = {zeta} }}\n"
            ),
        );
    }
    let mut m: Model = parse(&src, "map.toml")
        .map_err(|e| e.to_string())?
        .build()
        .map_err(|e| e.to_string())?;
    let c = m.coupled_mut().expect("coupled");
    let gain = scheme::gains(c, n).map_err(|e| e.to_string())?[0].gain;
    let omega_h = scheme::contact_omega(c) * c.granular.dt * n as f64;
    let choice = Choice {
        scheme,
        substeps: n,
        omega_dt: 0.0,
        body_omega_dt: 0.0,
        gains: Vec::new(),
        automatic: false,
        why: String::new(),
        warning: None,
        exact_overhead: 0.0,
        max_contacts: 0,
        fallback: None,
    };
    scheme::apply(c, &choice).map_err(|e| e.to_string())?;
    let mut meter = WorkMeter::new(m.coupled().expect("coupled"));
    let (mut diss, mut work, mut push, mut k) = (0.0f64, 0.0f64, 0.0, 0);
    for step in 1..=m.steps {
        m.step().map_err(|e| e.to_string())?;
        let c = m.coupled().expect("coupled");
        meter.after_step(&c.granular);
        if (0.015..0.045).contains(&c.granular.time) {
            push -= c.contacts.iter().map(|q| q.force.y).sum::<f64>();
            k += 1;
        }
        if step % n == 0 {
            let a = meter.account(c);
            diss = diss.max(a.diss.abs());
            work = work.max(a.w_ext.abs());
        }
    }
    let c = m.coupled().expect("coupled");
    let (created, exchanged) = c.subcycling_energy();
    let ratio = if exchanged > 0.0 {
        created / exchanged
    } else {
        0.0
    };
    Ok((diss / work, ratio, push / k as f64, gain, omega_h))
}

fn list<T: std::str::FromStr>(a: Option<&String>, d: &str) -> Vec<T> {
    a.map_or(d, |s| s.as_str())
        .split(',')
        .filter_map(|x| x.parse().ok())
        .collect()
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let moduli: Vec<f64> = list(args.get(1), "1e8,1e9,2e9,3e9,1e10");
    let ns: Vec<usize> = list(args.get(2), "5,10,20,50");
    let schemes: Vec<Scheme> = args
        .get(3)
        .map_or("predicted,compliant", |s| s.as_str())
        .split(',')
        .map(|s| match s {
            "predicted" => Scheme::Predicted,
            "compliant" => Scheme::Compliant,
            _ => panic!("schemes: predicted, compliant"),
        })
        .collect();
    let zeta: f64 = args.get(4).map_or(0.0, |z| z.parse().expect("zeta"));
    let mu: f64 = args.get(5).map_or(0.0, |z| z.parse().expect("friction"));
    let zeta = (zeta, mu);
    println!(
        "| E (Pa) | scheme | n | Γ | ω_c h | max \\|E_diss\\|/W | created / exchanged | mean reaction vs exact |"
    );
    println!("|---|---|---|---|---|---|---|---|");
    for &e in &moduli {
        let exact = run(e, zeta, Scheme::Exact, 1).expect("the exact step runs");
        println!(
            "| {e:e} | exact | 1 | — | {:.2} | {:.2} % | — | {:.0} N |",
            exact.4,
            100.0 * exact.0,
            exact.2
        );
        for &s in &schemes {
            for &n in &ns {
                match run(e, zeta, s, n) {
                    Ok((d, c, f, g, w)) => println!(
                        "| {e:e} | {} | {n} | {g:.3} | {w:.2} | {:.2} % | {:.2} % | {:+.2} % |",
                        s.name(),
                        100.0 * d,
                        100.0 * c,
                        100.0 * (f / exact.2 - 1.0)
                    ),
                    Err(err) => println!(
                        "| {e:e} | {} | {n} | | | stopped: {} | | |",
                        s.name(),
                        err.chars().take(120).collect::<String>()
                    ),
                }
            }
        }
    }
}
