//! The Rust API: a model assembled in code is the model the scenario file
//! describes (same defaults, same validation), bitwise.

use efgdem::scenario::body::{BcSpec, BodySpec, Edge, Elastic};
use efgdem::scenario::{self, Material, Probe, Scenario};

/// `examples/paper_cantilever_disc.toml` (Example 1), written in code.
fn example1_in_code() -> Scenario {
    let beam = BodySpec::new(
        "beam",
        [0.0, -0.1],
        [1.0, 0.2],
        [20, 4],
        Elastic::new(2.1e8, 0.3).density(2000.0).thickness(0.025),
    )
    .newmark(1.5, 0.8)
    .self_weight(false)
    .contact_edges(&[Edge::Top, Edge::Right])
    .bc(BcSpec::fixed(Edge::Left));
    Scenario::new()
        .dt(1.0e-4)
        .end_time(0.2)
        .gravity(0.0, -9.81)
        .add_material(Material::new("disc", 1000.0, 1.0e6, 1.0e6).friction(0.5))
        .discs("disc", &[[0.999999, 0.15, 0.05]])
        .add_body(beam)
        .add_probe(Probe::body_point("tip_uy", "beam", [1.0, 0.1], "uy"))
        .add_probe(Probe::disc("disc_uy", 1, "uy"))
}

#[test]
fn example1_built_in_code_equals_the_scenario_file_bitwise() {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/examples/paper_cantilever_disc.toml"
    );
    let file = scenario::load(std::path::Path::new(path)).expect("example 1");
    let code = example1_in_code();
    let (mut a, mut b) = (file.build().unwrap(), code.build().unwrap());
    assert_eq!(a.steps, 2000);
    assert_eq!((a.steps, a.dt), (b.steps, b.dt));
    let (pa, pb) = (file.probes(&a).unwrap(), code.probes(&b).unwrap());
    // the file's probes 0 and 2 are the code's 0 and 1
    let (tip_a, disc_a) = (&pa[0].1, &pa[2].1);
    let (tip_b, disc_b) = (&pb[0].1, &pb[1].1);
    let mut touched = false;
    for _ in 0..600 {
        a.step().unwrap();
        b.step().unwrap();
        assert_eq!(a.probe(tip_a).to_bits(), b.probe(tip_b).to_bits());
        assert_eq!(a.probe(disc_a).to_bits(), b.probe(disc_b).to_bits());
        touched |= !a.contacts().is_empty();
    }
    assert!(touched, "the disc is on the beam");
    let (ga, gb) = (a.granular().unwrap(), b.granular().unwrap());
    assert_eq!(ga.particles.pos, gb.particles.pos);
    assert_eq!(ga.particles.vel, gb.particles.vel);
    assert!(a.probe(tip_a) < 0.0, "the disc bends the beam down");
}

#[test]
fn code_built_scenarios_get_the_scenario_checks() {
    // a disc material without stiffness and a body with one node per row
    let bad = Scenario::new()
        .dt(1e-4)
        .steps(10)
        .add_material(Material::new("disc", 1000.0, -1.0, 1.0))
        .discs("disc", &[[0.0, 0.0, 1.0]])
        .add_body(BodySpec::new(
            "b",
            [0.0, 0.0],
            [1.0, 1.0],
            [1, 3],
            Elastic::new(1e6, 0.3),
        ));
    let e = bad.build().err().expect("invalid").to_string();
    assert!(e.contains("material[0].kn"), "{e}");
    assert!(e.contains("body[0].nodes"), "{e}");
}
