//! A run whose state stops being physical ends with exit code 3, naming the
//! step, the disc or body and the symptom, suggesting a time step, and
//! recording it in `summary.json` (issue 12); the history keeps the rows
//! before it, never a NaN.

#[allow(dead_code)]
mod common;
use common::{run_with, summary, tmpdir};

/// Two discs falling freely under a strong gravity (accepted: one step of
/// it moves a disc 1e-7 m) with nothing below them: after n steps a disc
/// moves n g Δt² = n · 1e-7 m per step, more than its radius (0.01 m) from
/// n = 1e5 on.
const FALLING: &str = r#"
[simulation]
dt = 1e-5
steps = 200000
gravity = [0.0, -1000.0]

[[material]]
name = "m"
density = 1000.0
kn = 1e6
ks = 1e6

[granular]
material = "m"
discs = [[0.0, 0.0, 0.01], [1.0, 0.0, 0.01]]

[[probe]]
name = "ke"
quantity = "kinetic"
"#;

#[test]
fn an_unphysical_state_stops_the_run_with_exit_3_and_a_diagnosis() {
    let root = tmpdir("unstable");
    let file = root.join("s.toml");
    std::fs::write(&file, FALLING).unwrap();
    let out = root.join("out");
    let o = run_with(&file, &out, &[]);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(3), "{stderr}");
    // the step at which n g Δt² first exceeds the radius (rounding decides
    // between the two)
    let s = summary(&out);
    assert_eq!(s["status"], "unstable");
    let step = s["instability"]["step"].as_u64().unwrap();
    assert!(step == 100_000 || step == 100_001, "{step}");
    // what the run reached, on stdout as for a completed run
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(stdout.contains("run unstable: "), "{stdout}");
    assert!(
        stderr.contains(&format!("unstable at step {step}")),
        "{stderr}"
    );
    assert!(
        stderr.contains("1.000e0 radii") && stderr.contains("try dt ="),
        "{stderr}"
    );
    let culprit = s["instability"]["culprit"].as_str().unwrap();
    assert!(culprit == "disc 1" || culprit == "disc 2", "{culprit}");
    // 0.2 × the critical step 2√(m/k), below the present dt
    let m = 1000.0 * std::f64::consts::PI * 1e-4;
    let suggested = s["instability"]["suggested_dt"].as_f64().unwrap();
    assert!((suggested - (0.2 * 2.0 * (m / 1e6f64).sqrt()).min(0.5e-5)).abs() < 1e-15);
    // rows every step up to the one before (output every 1 by default)
    let hist = std::fs::read_to_string(out.join("history.csv")).unwrap();
    assert_eq!(
        hist.lines().count() as u64,
        1 + step,
        "header, steps 0 … step − 1"
    );
    assert!(!hist.contains("NaN") && !hist.contains("inf"));
    // the blown-up state is not offered as a disc source
    assert!(!out.join("discs_final.csv").exists());
    std::fs::remove_dir_all(root).unwrap();
}

/// A body whose state turns non-finite is caught at the step, by name,
/// node and component.
#[test]
fn a_non_finite_body_is_caught_by_name_and_node() {
    use efgdem::model::body::Body;
    use efgdem::model::{ModelError, System};
    let mut m = efgdem::scenario::parse(
        r#"
[simulation]
analysis = "dynamic"
dt = 1e-3
steps = 10

[[body]]
name = "beam"
rectangle = { origin = [0.0, 0.0], size = [2.0, 0.5] }
nodes = [5, 3]
elastic = { E = 1e6, nu = 0.3, density = 10.0 }

[[body.bc]]
edge = "left"
fixed = true
"#,
        "<beam>",
    )
    .unwrap()
    .build()
    .unwrap();
    m.step().unwrap();
    let System::Continuum { bodies, .. } = &mut m.system else {
        unreachable!()
    };
    let Body::Efg(b) = &mut bodies[0] else {
        unreachable!()
    };
    b.state.v[7] = f64::NAN;
    match m.step() {
        Err(ModelError::Unstable(i)) => {
            assert_eq!((i.step, i.culprit.as_str()), (2, "body `beam`"));
            // the solve spreads the NaN velocity over every unknown: the
            // first non-finite displacement is reported
            assert!(
                i.symptom
                    .starts_with("non-finite displacement at node 1 (x"),
                "{}",
                i.symptom
            );
            assert_eq!(i.suggested_dt, 0.5e-3);
        }
        other => panic!("expected an instability, got {other:?}"),
    }
}
