//! What `efgdem run` prints on stdout when a run ends: a few lines with
//! the results that matter — how far it got, each probe's final value and
//! extremes (with their times), the energy balance, the discs removed for
//! bodies, and where the files are. Made from the run's `summary.json`
//! alone, so that it says nothing the files do not.

use serde_json::Value;
use std::fmt::Write as _;
use std::path::Path;

/// A number in a few significant digits: plain between 10⁻³ and 10⁵,
/// else in scientific notation.
fn num(x: f64) -> String {
    let a = x.abs();
    if x == 0.0 {
        "0".to_string()
    } else if (1e-3..1e5).contains(&a) {
        let digits = (3 - a.log10().floor() as i32).max(0) as usize;
        let s = format!("{x:.digits$}");
        match s.contains('.') {
            true => s.trim_end_matches('0').trim_end_matches('.').to_string(),
            false => s,
        }
    } else if x.is_finite() {
        format!("{x:.3e}")
    } else {
        x.to_string()
    }
}

fn f(v: &Value) -> f64 {
    v.as_f64().unwrap_or(f64::NAN)
}

/// The end-of-run text for `summary` (a run's `summary.json`) written
/// into `out`.
pub fn recap(summary: &Value, out: &Path) -> String {
    let mut s = String::new();
    let kind = summary["kind"].as_str().unwrap_or("continuum");
    let status = summary["status"].as_str().unwrap_or("completed");
    let _ = write!(s, "{kind} run {status}");
    if summary["analysis"] == "static" {
        s.push_str(": static solve");
    } else if let Some(n) = summary["last_step"].as_u64() {
        let dt = f(&summary["dt"]);
        let _ = write!(s, ": {n} steps, t = {} s", num(n as f64 * dt));
    }
    s.push('\n');
    probes(&mut s, &summary["probes"]);
    energy(&mut s, kind, summary);
    if let Some(m) = summary["removed_discs"].as_object() {
        for (body, n) in m {
            let _ = writeln!(s, "removed {n} disc(s) overlapping body `{body}`");
        }
    }
    files(&mut s, out);
    s
}

/// One line per probe: final, min (t), max (t).
fn probes(s: &mut String, probes: &Value) {
    let Some(m) = probes.as_object().filter(|m| !m.is_empty()) else {
        return;
    };
    let w = m.keys().map(|k| k.chars().count()).max().unwrap_or(0);
    s.push_str("probes (final; min, max over history.csv):\n");
    for (name, e) in m {
        let at = |k: &str| match e[k].as_f64() {
            Some(t) => format!(" at t = {}", num(t)),
            None => String::new(),
        };
        let sign = match e["sign"].as_str() {
            Some(s) => format!("  ({s})"),
            None => String::new(),
        };
        let _ = writeln!(
            s,
            "  {name:<w$}  {:>10};  min {}{},  max {}{}{sign}",
            num(f(&e["final"])),
            num(f(&e["min"])),
            at("t_min"),
            num(f(&e["max"])),
            at("t_max"),
        );
    }
}

/// The energy balance of the kind of run.
fn energy(s: &mut String, kind: &str, summary: &Value) {
    match kind {
        "coupled" => {
            let e = &summary["energy"];
            let stored: f64 = [
                "E_kin_dem",
                "E_kin_body",
                "E_strain",
                "E_penalty",
                "E_contact",
            ]
            .iter()
            .map(|k| f(&e[*k]))
            .sum();
            let (w, d) = (f(&e["W_ext"]), f(&e["E_diss"]));
            let share = match w.abs() > 0.0 {
                true => format!(" ({:.1} % of W_ext)", 100.0 * d / w),
                false => String::new(),
            };
            // a run with growing cracks: the energy the growth took
            let (plus, fracture) = match e["E_fracture"].as_f64() {
                Some(fr) if fr != 0.0 => (
                    " + fracture",
                    format!("; taken by crack growth E_fracture = {} J", num(fr)),
                ),
                _ => ("", String::new()),
            };
            let _ = writeln!(
                s,
                "energy: work done W_ext = {} J = stored change{plus} + dissipated; stored now {} J (kinetic {} + {}, strain {}, contact {}){fracture}; dissipated E_diss = {} J{share}",
                num(w),
                num(stored),
                num(f(&e["E_kin_dem"])),
                num(f(&e["E_kin_body"])),
                num(f(&e["E_strain"]) + f(&e["E_penalty"])),
                num(f(&e["E_contact"])),
                num(d),
            );
        }
        "granular" => {
            let e = &summary["energies"];
            let _ = writeln!(
                s,
                "energy of the discs at the end: kinetic {} J, rotational {} J, contact springs {} J, gravity potential {} J",
                num(f(&e["kinetic"])),
                num(f(&e["rotational"])),
                num(f(&e["spring"])),
                num(f(&e["gravity"])),
            );
        }
        _ => {
            if let Some(bodies) = summary["bodies"].as_array() {
                for b in bodies.iter().filter(|b| b["strain_energy"].is_number()) {
                    let _ = writeln!(
                        s,
                        "body `{}`: strain energy {} J, kinetic energy {} J",
                        b["name"].as_str().unwrap_or("?"),
                        num(f(&b["strain_energy"])),
                        num(f(&b["kinetic_energy"])),
                    );
                }
            }
        }
    }
}

/// Where the results are, and how to look at them.
fn files(s: &mut String, out: &Path) {
    let Ok(dir) = std::fs::read_dir(out) else {
        return;
    };
    let mut names: Vec<String> = dir
        .filter_map(Result::ok)
        .map(|e| e.file_name().to_string_lossy().into_owned())
        // not the frames' folder, temporary or hidden files (the lock)
        .filter(|n| !n.ends_with(".tmp") && !n.starts_with('.') && n != "frames")
        .collect();
    names.sort();
    let _ = writeln!(s, "files in {}: {}", out.display(), names.join(", "));
    if names
        .iter()
        .any(|n| n.ends_with(".pvd") || n.ends_with(".vtu"))
    {
        let _ = writeln!(s, "look at them: efgdem view {}", out.display());
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_keep_four_significant_digits() {
        assert_eq!(num(0.0), "0");
        assert_eq!(num(1234.5678), "1235");
        assert_eq!(num(-0.012345), "-0.01235");
        assert_eq!(num(2.5), "2.5");
        assert_eq!(num(1.5e-7), "1.500e-7");
        assert_eq!(num(123456.0), "1.235e5");
    }
}
