//! Building granular assemblies from scenario text: every disc source.

use efgdem::scenario;

fn scenario_with(discs: &str, extra: &str) -> String {
    format!(
        r#"[simulation]
steps = 10
gravity = [0.0, -9.81]

[[material]]
name = "g"
density = 1.0
kn = 1e5
ks = 1e5
friction = 0.5

[granular]
material = "g"
discs = {discs}
damping = {{ kind = "local", alpha = 0.7 }}
{extra}
"#
    )
}

fn build_from(text: &str) -> efgdem::dem::Granular {
    let sc = scenario::parse(text, "t.toml").unwrap_or_else(|e| panic!("{e}"));
    sc.build()
        .unwrap_or_else(|e| panic!("{e}"))
        .into_granular()
        .unwrap()
}

#[test]
fn lattices_fill_the_box() {
    let g = build_from(&scenario_with(
        r#"{ generate = "square", box = [[0, 0], [10, 4]], radius = 1.0 }"#,
        "",
    ));
    assert_eq!(g.particles.len(), 10);
    let g = build_from(&scenario_with(
        r#"{ generate = "hex", box = [[0, 0], [10, 10]], radius = 1.0, count = 12 }"#,
        "",
    ));
    assert_eq!(g.particles.len(), 12);
    // default dt: DT_SAFETY × the critical step of the contacts in use
    let crit = g.critical_step(&[]).dt;
    assert!((g.dt / crit - efgdem::dem::DT_SAFETY).abs() < 1e-12);
}

#[test]
fn random_deposit_settles_into_the_box() {
    let g = build_from(&scenario_with(
        r#"{ generate = "random", box = [[0, 0], [30, 80]], radius = [0.8, 1.2], count = 300, seed = 4, method = "deposit", settle_steps = 4000 }"#,
        "",
    ));
    assert_eq!(g.particles.len(), 300);
    let p = &g.particles;
    let top = p.pos.iter().map(|q| q.y).fold(0.0, f64::max);
    // 300 discs of mean area π in a 30-wide box: a bed about 40 high once
    // settled, well below the loose packing's top
    assert!(top < 45.0, "top {top}");
    assert!(p.pos.iter().all(|q| q.x > 0.0 && q.x < 30.0 && q.y > 0.0));
}

#[test]
fn csv_source_and_per_disc_material() {
    let dir = std::env::temp_dir().join(format!("efgdem-demsc-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("d.csv"), "x,y,r,material\n0,1,1,g\n3,1,0.5,h\n").unwrap();
    let text = scenario_with(r#"{ csv = "d.csv" }"#, "").replace(
        "[granular]",
        "[[material]]\nname = \"h\"\ndensity = 2.0\nkn = 2e5\nks = 2e5\nfriction = 0.3\n\n[granular]",
    );
    let path = dir.join("s.toml");
    std::fs::write(&path, text).unwrap();
    let sc = scenario::load(&path).unwrap();
    let g = sc.build().unwrap().into_granular().unwrap();
    assert_eq!(g.particles.len(), 2);
    assert_eq!(g.particles.material, vec![0, 1]);
    // mixed law: stiffness 2 k1 k2 / (k1 + k2), friction the smaller
    let l = g.law(0, 1);
    assert!((l.kn - 2.0 * 1e5 * 2e5 / 3e5).abs() < 1e-6);
    assert_eq!(l.mu, 0.3);
    let m1 = std::f64::consts::PI * 0.25 * 2.0;
    assert!((g.particles.mass[1] - m1).abs() < 1e-12);
    assert!((g.particles.inertia[1] - 0.5 * m1 * 0.25).abs() < 1e-12);
}

#[test]
fn piecewise_wall_history_moves_the_wall() {
    let g = {
        let mut g = build_from(&scenario_with(
            "[[0.0, 5.0, 1.0]]",
            "\n[[wall]]\nname = \"w\"\nfrom = [-5.0, 0.0]\nto = [5.0, 0.0]\nhistory = [[0.0, 0.0, 0.0], [1.0, 0.0, 2.0]]\n",
        ));
        g.dt = 0.01;
        for _ in 0..100 {
            g.step();
        }
        g
    };
    // v(t) = 2t on [0, 1]: displacement 1 at t = 1 (exact with midpoint sampling)
    assert!((g.walls[0].a.y - 1.0).abs() < 1e-12, "{}", g.walls[0].a.y);
}

#[test]
fn radius_growth_fills_the_box_densely() {
    let g = build_from(&scenario_with(
        r#"{ generate = "random", box = [[0, 0], [40, 40]], radius = [0.8, 1.2], count = 400, seed = 9, method = "grow", settle_steps = 6000 }"#,
        "",
    ));
    let p = &g.particles;
    assert_eq!(p.len(), 400);
    let area: f64 = p.radius.iter().map(|r| std::f64::consts::PI * r * r).sum();
    assert!(area / 1600.0 > 0.75, "packing fraction {}", area / 1600.0);
    // final radii in range, inside the box, overlaps small
    assert!(p.radius.iter().all(|&r| (0.8..=1.2).contains(&r)));
    assert!(p.pos.iter().zip(&p.radius).all(|(q, r)| q.x > 0.0
        && q.x < 40.0
        && q.y > 0.0
        && q.y < 40.0
        && *r > 0.0));
    let mut worst = 0.0f64;
    for i in 0..p.len() {
        for j in i + 1..p.len() {
            let ov = p.radius[i] + p.radius[j] - (p.pos[i] - p.pos[j]).norm();
            worst = worst.max(ov / p.radius[i].min(p.radius[j]));
        }
    }
    println!(
        "packing fraction {:.3}, worst overlap {worst:.2e} r",
        area / 1600.0
    );
    // near jamming the soft contacts keep small overlaps
    assert!(worst < 0.1, "worst relative overlap {worst}");
}
