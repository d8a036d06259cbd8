//! Servo-controlled and strain-rate walls (issue 13 §3): a servo wall
//! holds its stress and stops, never faster than `max_velocity`; a
//! strain-rate wall follows `D_{n+1} = D_n (1 − ε̇Δt)` ≈ `D₀ e^{−ε̇t}`;
//! walls joined at the corners of a shrinking or widening box keep every
//! disc inside.

use efgdem::dem::Granular;
use efgdem::dem::measure::{self, Region};
use efgdem::geom::Vec2;
use efgdem::model::Model;
use efgdem::scenario;

fn build(src: &str) -> Model {
    scenario::parse(src, "t.toml")
        .unwrap_or_else(|e| panic!("{e}"))
        .build()
        .unwrap_or_else(|e| panic!("{e}"))
}

fn wall<'a>(g: &'a Granular, name: &str) -> &'a efgdem::dem::walls::Wall {
    g.walls.iter().find(|w| w.name == name).unwrap()
}

const MATERIALS: &str = r#"
[[material]]
name = "sand"
density = 2650.0
kn = 1.0e6
ks = 5.0e5
friction = 0.5

[[material]]
name = "smooth"
kn = 1.0e6
"#;

/// Loose discs in the box [0, 0.1]², frictionless walls: `walls` are the
/// four `[[wall]]` tables.
fn boxed(end_time: f64, walls: &str) -> String {
    format!(
        r#"
[simulation]
end_time = {end_time}
{MATERIALS}
[granular]
material = "sand"
discs = {{ generate = "random", box = [[0.0, 0.0], [0.1, 0.1]], radius = [0.002, 0.003], seed = 5 }}
damping = {{ kind = "critical-ratio", zeta = 0.2 }}
{walls}
"#
    )
}

fn wall_toml(name: &str, from: [f64; 2], to: [f64; 2], motion: &str) -> String {
    format!(
        "[[wall]]\nname = \"{name}\"\nfrom = {from:?}\nto = {to:?}\nmaterial = \"smooth\"\n{motion}\n"
    )
}

/// The box between the four walls' lines: (x_left, x_right, y_floor, y_top).
fn box_of(g: &Granular) -> (f64, f64, f64, f64) {
    (
        wall(g, "left").a.x,
        wall(g, "right").a.x,
        wall(g, "floor").a.y,
        wall(g, "top").a.y,
    )
}

/// Every disc inside the box, by at least `margin` × its radius from each
/// wall line; returns the smallest clearance / r.
fn clearance(g: &Granular) -> f64 {
    let (x0, x1, y0, y1) = box_of(g);
    let p = &g.particles;
    (0..p.len())
        .map(|k| {
            let (x, r) = (p.pos[k], p.radius[k]);
            [x.x - x0, x1 - x.x, x.y - y0, y1 - x.y]
                .into_iter()
                .fold(f64::INFINITY, f64::min)
                / r
        })
        .fold(f64::INFINITY, f64::min)
}

/// The Love–Weber stress of the whole box between the walls.
fn box_stress(g: &Granular) -> [f64; 3] {
    let (x0, x1, y0, y1) = box_of(g);
    let region = Region::Rectangle {
        lo: Vec2::new(x0, y0),
        hi: Vec2::new(x1, y1),
    };
    measure::contacts(g, &region, []).stress
}

#[test]
fn servo_wall_holds_its_stress_and_stops() {
    let (sigma, vmax) = (1.0e5, 0.5);
    let walls = [
        wall_toml("floor", [0.0, 0.0], [0.1, 0.0], ""),
        wall_toml("left", [0.0, 0.0], [0.0, 0.1], ""),
        wall_toml("right", [0.1, 0.0], [0.1, 0.1], ""),
        wall_toml(
            "top",
            [0.0, 0.1],
            [0.1, 0.1],
            &format!("servo = {{ stress = {sigma}, max_velocity = {vmax} }}"),
        ),
    ]
    .concat();
    let mut m = build(&boxed(0.3, &walls));
    let mut vpeak = 0.0f64;
    let mut history = vec![];
    while m.step < m.steps {
        m.step().unwrap();
        let g = m.granular().unwrap();
        let top = wall(g, "top");
        vpeak = vpeak.max(top.vel.norm());
        history.push((top.normal_stress(g.thickness), top.vel.y));
    }
    let g = m.granular().unwrap();
    let top = wall(g, "top");
    let s = top.normal_stress(g.thickness);
    // the servo's own measure of the force, and the wall's
    assert!(
        (top.normal_force() / (top.length() * g.thickness) - s).abs() < 1e-9 * s,
        "{s}"
    );
    let err = (s - sigma) / sigma;
    eprintln!(
        "servo top wall: σ = {s:.6e} (error {err:.2e}), v = {:.3e} m/s at the end, peak {vpeak} (max {vmax}); wall moved {:.4} m; {} discs touching it",
        top.vel.y,
        0.1 - top.a.y,
        top.contacts
    );
    assert!(err.abs() < 0.01, "stress error {err}");
    // stopped: the last 1000 steps within 1 % of σ and at < 1e-3 of max_velocity
    for &(si, v) in &history[history.len() - 1000..] {
        assert!(((si - sigma) / sigma).abs() < 0.01, "{si}");
        assert!(v.abs() < 1e-3 * vmax, "{v}");
    }
    // max_velocity respected, and reached while closing in
    assert!(vpeak <= vmax, "{vpeak}");
    assert_eq!(vpeak, vmax);
    // walls frictionless: the box measures the walls' stresses (§4)
    let st = box_stress(g);
    let side = (wall(g, "left").normal_stress(1.0) + wall(g, "right").normal_stress(1.0)) / 2.0;
    eprintln!(
        "box measure: σ_yy = {:.6e} vs top {s:.6e}; σ_xx = {:.6e} vs sides {side:.6e}; σ_xy = {:.3e}",
        st[1], st[0], st[2]
    );
    assert!(((st[1] - s) / s).abs() < 0.02);
    assert!(((st[0] - side) / side).abs() < 0.02);
    assert!(clearance(g) > 0.5);
}

/// Four servo walls (isotropic compression to σ) joined at the corners:
/// every wall at σ, the box closed at the corners, no disc outside.
#[test]
fn four_servo_walls_compress_a_box_isotropically() {
    let sigma = 5.0e4;
    let servo = format!("servo = {{ stress = {sigma}, max_velocity = 0.3 }}");
    let walls = [
        wall_toml("floor", [0.0, 0.0], [0.1, 0.0], &servo),
        wall_toml("left", [0.0, 0.0], [0.0, 0.1], &servo),
        wall_toml("right", [0.1, 0.0], [0.1, 0.1], &servo),
        wall_toml("top", [0.0, 0.1], [0.1, 0.1], &servo),
    ]
    .concat();
    let mut m = build(&boxed(0.3, &walls));
    let mut worst = f64::INFINITY;
    while m.step < m.steps {
        m.step().unwrap();
        if m.step.is_multiple_of(50) {
            worst = worst.min(clearance(m.granular().unwrap()));
        }
    }
    let g = m.granular().unwrap();
    for w in &g.walls {
        let s = w.normal_stress(g.thickness);
        eprintln!(
            "{}: σ = {s:.6e} (error {:.2e}), length {:.5}, v = {:.2e}",
            w.name,
            (s - sigma) / sigma,
            w.length(),
            w.vel.norm()
        );
        assert!(((s - sigma) / sigma).abs() < 0.01, "{}: {s}", w.name);
        assert!(w.joins[0].is_some() && w.joins[1].is_some(), "{}", w.name);
    }
    // the corners stay closed: each wall ends on the two walls it meets
    let (x0, x1, y0, y1) = box_of(g);
    let close = |p: Vec2, q: Vec2| (p - q).norm() < 1e-12;
    assert!(close(wall(g, "floor").a, Vec2::new(x0, y0)));
    assert!(close(wall(g, "floor").b, Vec2::new(x1, y0)));
    assert!(close(wall(g, "left").b, Vec2::new(x0, y1)));
    assert!(close(wall(g, "right").b, Vec2::new(x1, y1)));
    assert!(close(wall(g, "top").a, Vec2::new(x0, y1)));
    assert!(close(wall(g, "top").b, Vec2::new(x1, y1)));
    eprintln!(
        "box {:.5} × {:.5} (from 0.1 × 0.1); smallest clearance of a disc from a wall during the run: {worst:.3} r",
        x1 - x0,
        y1 - y0
    );
    assert!(x1 - x0 < 0.09 && y1 - y0 < 0.09, "the box shrank");
    assert!(worst > 0.5, "a disc left the box: clearance {worst} r");
    let st = box_stress(g);
    eprintln!(
        "box measure: σ_xx = {:.6e}, σ_yy = {:.6e}, σ_xy = {:.2e} (σ = {sigma:e})",
        st[0], st[1], st[2]
    );
    assert!(((st[0] - sigma) / sigma).abs() < 0.02);
    assert!(((st[1] - sigma) / sigma).abs() < 0.02);
}

/// One disc far from the walls; `top` and `floor` as given.
fn two_walls(top: &str, floor: &str, dt: f64, steps: usize) -> String {
    format!(
        r#"
[simulation]
dt = {dt}
steps = {steps}
{MATERIALS}
[granular]
material = "sand"
discs = [[0.5, 0.5, 0.01]]

[[wall]]
name = "floor"
from = [0.0, 0.0]
to = [1.0, 0.0]
{floor}

[[wall]]
name = "top"
from = [0.0, 1.0]
to = [1.0, 1.0]
{top}
"#
    )
}

#[test]
fn strain_rate_wall_follows_its_law() {
    let (rate, dt, n) = (2.0, 1e-5, 20_000);
    for (floor, who) in [("", "top alone"), ("strain_rate = 2.0", "top and floor")] {
        let mut m = build(&two_walls("strain_rate = 2.0", floor, dt, n));
        let d0 = 1.0;
        let mut worst_exact = 0.0f64;
        let mut worst_exp = 0.0f64;
        for k in 1..=n {
            m.step().unwrap();
            if k % 1000 == 0 {
                let g = m.granular().unwrap();
                let d = wall(g, "top").a.y - wall(g, "floor").a.y;
                let exact = d0 * (1.0 - rate * dt).powi(k as i32);
                let cont = d0 * (-rate * k as f64 * dt).exp();
                worst_exact = worst_exact.max((d / exact - 1.0).abs());
                worst_exp = worst_exp.max((d / cont - 1.0).abs());
                if !floor.is_empty() {
                    // symmetric: the middle stays put
                    let mid = 0.5 * (wall(g, "top").a.y + wall(g, "floor").a.y);
                    assert!((mid - 0.5).abs() < 1e-12, "{mid}");
                }
            }
        }
        let g = m.granular().unwrap();
        let d = wall(g, "top").a.y - wall(g, "floor").a.y;
        eprintln!(
            "{who}: D(t = {}) = {d:.9} vs D₀(1 − ε̇Δt)^n: rel. {worst_exact:.1e}, vs D₀ e^(−ε̇t) = {:.9}: rel. {worst_exp:.1e}",
            n as f64 * dt,
            (-rate * n as f64 * dt).exp()
        );
        assert!(worst_exact < 1e-12);
        // (1 − ε̇Δt)^n = e^{−ε̇t} (1 − ε̇²Δt t/2 + …)
        assert!(worst_exp < 0.6 * rate * rate * dt * n as f64 * dt);
    }
    // negative rate: extension
    let mut m = build(&two_walls("strain_rate = -1.0", "", dt, 1000));
    for _ in 0..1000 {
        m.step().unwrap();
    }
    let top = wall(m.granular().unwrap(), "top").a.y;
    assert!((top - (1.0 + dt).powi(1000)).abs() < 1e-12, "{top}");
}

/// A dense packing compressed between strain-rate platens while servo
/// side walls hold a small confining stress: the sample widens, the
/// platens stretch with the side walls and no disc leaks at the corners.
/// The same run with the platens' ends not joined loses discs.
fn biaxial(joined: bool) -> (f64, f64, f64, f64) {
    let servo = "servo = { stress = 2.0e4, max_velocity = 0.1 }";
    let walls = [
        wall_toml("floor", [0.0, 0.0], [0.1, 0.0], "strain_rate = 0.5"),
        wall_toml("left", [0.0, 0.0], [0.0, 0.1], servo),
        wall_toml("right", [0.1, 0.0], [0.1, 0.1], servo),
        wall_toml("top", [0.0, 0.1], [0.1, 0.1], "strain_rate = 0.5"),
    ]
    .concat();
    let src = format!(
        r#"
[simulation]
end_time = 0.4
{MATERIALS}
[granular]
material = "sand"
discs = {{ generate = "random", method = "grow", box = [[0.0, 0.0], [0.1, 0.1]], radius = [0.002, 0.003], count = 400, seed = 2, settle_steps = 6000 }}
damping = {{ kind = "critical-ratio", zeta = 0.2 }}
{walls}
"#
    );
    let mut m = build(&src);
    if !joined && let efgdem::model::System::Granular(g) = &mut m.system {
        for w in &mut g.walls {
            w.joins = [None, None];
        }
    }
    let mut worst = f64::INFINITY;
    while m.step < m.steps {
        m.step().unwrap();
        if m.step.is_multiple_of(50) {
            worst = worst.min(clearance(m.granular().unwrap()));
        }
    }
    let g = m.granular().unwrap();
    let (x0, x1, y0, y1) = box_of(g);
    (x1 - x0, y1 - y0, worst, wall(g, "floor").length())
}

#[test]
fn joined_walls_keep_discs_in_a_widening_box() {
    let (w, h, worst, floor) = biaxial(true);
    eprintln!(
        "joined: box {w:.5} × {h:.5} (from 0.1 × 0.1, ε̇ = 0.5 for 0.4 s: h = {:.5}), floor length {floor:.5}, smallest clearance {worst:.3} r",
        0.1 * (-0.2f64).exp()
    );
    assert!(w > 0.102, "the sample widened: {w}");
    assert!((floor - w).abs() < 1e-12, "the floor spans the box");
    assert!(worst > 0.5, "a disc left the box: clearance {worst} r");
    let (w2, _, worst2, floor2) = biaxial(false);
    eprintln!("not joined: box width {w2:.5}, floor length {floor2:.5}, clearance {worst2:.3} r");
    assert!(worst2 < 0.0, "without joins discs leak at the corners");
}

#[test]
fn servo_and_strain_rate_fields_are_checked() {
    let err = |walls: &str| {
        scenario::parse(&boxed(0.01, walls), "w.toml")
            .and_then(|s| s.build().map(|_| ()))
            .unwrap_err()
            .to_string()
    };
    let base = |motion: &str| {
        [
            wall_toml("floor", [0.0, 0.0], [0.1, 0.0], ""),
            wall_toml("top", [0.0, 0.1], [0.1, 0.1], motion),
        ]
        .concat()
    };
    let e = err(&base(
        "velocity = [0.0, -1.0]\nservo = { stress = 1.0, max_velocity = 0.1 }",
    ));
    assert!(e.contains("wall[1].servo: give one motion"), "{e}");
    let e = err(&base("servo = { stress = 1.0, max_velocity = 0.0 }"));
    assert!(
        e.contains("wall[1].servo.max_velocity: must be a finite number > 0"),
        "{e}"
    );
    let e = err(&base(
        "servo = { stress = 1.0, max_velocity = 0.1, relaxation = 1.5 }",
    ));
    assert!(
        e.contains("wall[1].servo.relaxation: must be in (0, 1]"),
        "{e}"
    );
    // too fast for the time step: it could pass through a disc
    let e = err(&base("servo = { stress = 1.0, max_velocity = 100.0 }"));
    assert!(
        e.contains("wall[1].servo.max_velocity: wall `top` would move"),
        "{e}"
    );
    let e = err(&[
        wall_toml("floor", [0.0, 0.0], [0.1, 0.0], ""),
        wall_toml("left", [0.0, 0.0], [0.0, 0.1], "strain_rate = 1.0"),
    ]
    .concat());
    assert!(
        e.contains("wall[1].strain_rate: needs a wall parallel"),
        "{e}"
    );
    let e = err(&[
        wall_toml("floor", [0.0, 0.0], [0.1, 0.0], "strain_rate = 2.0"),
        wall_toml("top", [0.0, 0.1], [0.1, 0.1], "strain_rate = 1.0"),
    ]
    .concat());
    assert!(e.contains("share one rate"), "{e}");
}

/// `phases`: a servo wall (no disc touches it: it runs in at
/// `max_velocity`) that follows a strain rate from step 1000 on, then
/// stops at step 1500: the distance is `D₀ − v N Δt`, then
/// `D_N (1 − ε̇Δt)^(n − N)`, then constant.
#[test]
fn a_wall_changes_its_motion_at_the_steps_of_its_phases() {
    let (dt, v, rate) = (1e-5, 0.5, 2.0);
    let top = format!(
        "phases = [{{ until_step = 1000, servo = {{ stress = 1.0e6, max_velocity = {v} }} }}, {{ until_step = 1500, strain_rate = {rate} }}]"
    );
    let mut m = build(&two_walls(&top, "", dt, 2000));
    let d = |m: &Model| {
        let g = m.granular().unwrap();
        wall(g, "top").a.y - wall(g, "floor").a.y
    };
    for _ in 0..1000 {
        m.step().unwrap();
    }
    let dn = d(&m);
    assert!((dn - (1.0 - v * 1000.0 * dt)).abs() < 1e-12, "{dn}");
    for _ in 0..500 {
        m.step().unwrap();
    }
    let exact = dn * (1.0 - rate * dt).powi(500);
    assert!((d(&m) / exact - 1.0).abs() < 1e-12, "{} {exact}", d(&m));
    let stop = d(&m);
    for _ in 0..500 {
        m.step().unwrap();
    }
    assert_eq!(d(&m), stop, "at rest after the last phase");
    eprintln!(
        "servo phase: D = {dn:.6}; strain-rate phase: D = {stop:.9} (exact {exact:.9}); then at rest"
    );
}

#[test]
fn wall_phases_are_checked() {
    let err = |walls: &str| {
        scenario::parse(&boxed(0.01, walls), "w.toml")
            .and_then(|s| s.build().map(|_| ()))
            .unwrap_err()
            .to_string()
    };
    let base = |motion: &str| {
        [
            wall_toml("floor", [0.0, 0.0], [0.1, 0.0], ""),
            wall_toml("top", [0.0, 0.1], [0.1, 0.1], motion),
        ]
        .concat()
    };
    let servo = "servo = { stress = 1.0, max_velocity = 0.1 }";
    let e = err(&base(&format!(
        "{servo}\nphases = [{{ until_step = 10, {servo} }}, {{ strain_rate = 1.0 }}]"
    )));
    assert!(
        e.contains("wall[1].phases: give the motion either in `phases`"),
        "{e}"
    );
    let e = err(&base(&format!(
        "phases = [{{ {servo} }}, {{ strain_rate = 1.0 }}]"
    )));
    assert!(
        e.contains("wall[1].phases[0].until_step: every phase but the last needs `until_step`"),
        "{e}"
    );
    let e = err(&base(&format!(
        "phases = [{{ until_step = 10, {servo} }}, {{ until_step = 10, strain_rate = 1.0 }}]"
    )));
    assert!(
        e.contains("wall[1].phases[1].until_step: must be greater than 10"),
        "{e}"
    );
    let e = err(&base(&format!(
        "phases = [{{ until_step = 10, {servo}, velocity = [0.0, 1.0] }}]"
    )));
    assert!(
        e.contains("wall[1].phases[0].servo: give one motion"),
        "{e}"
    );
    let e = err(&base(
        "phases = [{ until_step = 10, servo = { stress = 1.0, max_velocity = 100.0 } }]",
    ));
    assert!(
        e.contains("wall[1].phases[0].servo.max_velocity: wall `top` would move"),
        "{e}"
    );
    let e = err(&base(
        "phases = [{ until_step = 10, servo = { stress = 1.0, max_velocity = 0.1, integral = 1.0 } }]",
    ));
    assert!(
        e.contains("wall[1].phases[0].servo.integral: must be in [0, 1)"),
        "{e}"
    );
    // facing strain-rate phases over steps that only partly overlap
    let e = err(&[
        wall_toml(
            "floor",
            [0.0, 0.0],
            [0.1, 0.0],
            "phases = [{ until_step = 10 }, { strain_rate = 1.0 }]",
        ),
        wall_toml(
            "top",
            [0.0, 0.1],
            [0.1, 0.1],
            "phases = [{ until_step = 20 }, { strain_rate = 1.0 }]",
        ),
    ]
    .concat());
    assert!(
        e.contains("wall[0].phases[1].strain_rate: the opposite wall `top` has strain_rate = 1 over steps 20.., this wall 1 over steps 10..: two facing strain-rate walls share one rate"),
        "{e}"
    );
    // the same steps: fine, half each
    let ok = [
        wall_toml(
            "floor",
            [0.0, 0.0],
            [0.1, 0.0],
            "phases = [{ until_step = 10 }, { strain_rate = 1.0 }]",
        ),
        wall_toml(
            "top",
            [0.0, 0.1],
            [0.1, 0.1],
            "phases = [{ until_step = 10 }, { strain_rate = 1.0 }]",
        ),
    ]
    .concat();
    let m = build(&boxed(0.01, &ok));
    for w in &m.granular().unwrap().walls {
        let efgdem::dem::walls::WallMotion::Phases(p) = &w.motion else {
            panic!("phases")
        };
        assert_eq!(
            p[1].motion,
            efgdem::dem::walls::WallMotion::StrainRate {
                rate: 1.0,
                opposite: 1 - (w.name == "top") as usize,
                share: 0.5
            }
        );
    }
}
