//! Polygon EFG bodies (issue 15): patch tests on an L-shape and a holed
//! square, Kirsch's plate with a hole, Lamé's ring under internal
//! pressure, the visibility criterion.

use efgdem::continuum::{
    BodyParams, EdgeCondition, Elastic, KirschSpec, LinearField, PolygonShape, Prescribed,
    Rectangle, Refine,
};
use efgdem::efg::EfgBody;
use efgdem::geom::Vec2;
use efgdem::geom::polygon::{Domain, circle};

fn v(p: &[[f64; 2]]) -> Vec<Vec2> {
    p.iter().map(|&a| a.into()).collect()
}

/// All segments of loop `k` of `n` vertices.
fn whole(k: usize, n: usize) -> Vec<(usize, usize)> {
    (0..n).map(|i| (k, i)).collect()
}

fn params(domain: Domain, h: f64, gauss: usize, el: Elastic, bc: Vec<EdgeCondition>) -> BodyParams {
    let (lo, hi) = domain.bounds();
    let mut p = BodyParams::new(
        "poly",
        Rectangle {
            origin: lo.to_array(),
            size: (hi - lo).to_array(),
        },
        [2, 2],
        el,
    );
    p.polygon = Some(PolygonShape {
        domain,
        spacing: h,
        refine: Vec::new(),
    });
    p.gauss = gauss;
    p.bc = bc;
    p.self_weight = false;
    // α = 1e8 E: the penalty's O(1/α) boundary error is 5e-4 of the
    // stress at the default 1e5 E (measured on the L-shape)
    p.penalty = Some(1e8 * p.elastic.e);
    p
}

const UX: [f64; 3] = [1e-3, 2e-3, 3e-3];
const UY: [f64; 3] = [-1e-3, 1e-3, -2e-3];

fn linear_bc(edge: &str) -> EdgeCondition {
    EdgeCondition {
        ux: Some(Prescribed::Linear(LinearField { linear: UX })),
        uy: Some(Prescribed::Linear(LinearField { linear: UY })),
        ..EdgeCondition::on(edge)
    }
}

/// Max relative displacement error at the nodes and stress error at the
/// domain Gauss points farther than `h` from the boundary.
fn patch_errors(b: &EfgBody, h: f64) -> (f64, f64) {
    let ex = [UX[1], UY[2], UX[2] + UY[1]];
    let se = b.material.stress(ex);
    let smax = se.iter().fold(0.0f64, |m, s| m.max(s.abs()));
    let mesh = b.mesh.as_ref().unwrap();
    let (mut eu, mut es) = (0.0f64, 0.0f64);
    for q in mesh.domain_points(1) {
        let s = b.sample(q.x).unwrap();
        let p = q.x;
        let u = [
            UX[0] + UX[1] * p.x + UX[2] * p.y,
            UY[0] + UY[1] * p.x + UY[2] * p.y,
        ];
        eu = eu.max((s.u.x - u[0]).abs().max((s.u.y - u[1]).abs()) / 1e-2);
        if mesh.domain.boundary_distance(p) > h {
            for (sk, ek) in s.stress.iter().zip(&se) {
                es = es.max((sk - ek).abs() / smax);
            }
        }
    }
    (eu, es)
}

fn l_shape(h: f64, gauss: usize) -> (f64, f64) {
    l_shape_refined(h, gauss, None)
}

/// The L-shape patch test, with `refine = Some((h_r, width))` nodes at
/// `h_r` near the two edges of the re-entrant corner.
fn l_shape_refined(h: f64, gauss: usize, refine: Option<(f64, f64)>) -> (f64, f64) {
    let outline = v(&[
        [0.0, 0.0],
        [2.0, 0.0],
        [2.0, 1.0],
        [1.0, 1.0],
        [1.0, 2.0],
        [0.0, 2.0],
    ]);
    let d = Domain::new(outline, vec![], vec![("outer".into(), whole(0, 6))]).unwrap();
    let mut p = params(
        d,
        h,
        gauss,
        Elastic::new(1000.0, 0.25),
        vec![linear_bc("outer")],
    );
    if let Some((spacing, width)) = refine {
        p.polygon.as_mut().unwrap().refine.push(Refine {
            segments: vec![(0, 2), (0, 3)],
            spacing,
            width,
        });
    }
    let mut b = EfgBody::new(&p, [0.0, 0.0]).unwrap();
    b.solve_static().unwrap();
    let e = patch_errors(&b, h);
    println!(
        "L-shape patch, h = {h}, gauss = {gauss}, refine {refine:?}: {} nodes, displacement error {:.2e}, interior stress error {:.2e}",
        b.n_nodes(),
        e.0,
        e.1
    );
    e
}

fn holed_square(h: f64, gauss: usize) -> (f64, f64) {
    holed_square_refined(h, gauss, None)
}

/// The holed-square patch test, with `refine = Some((h_r, width))` nodes
/// at `h_r` near the hole.
fn holed_square_refined(h: f64, gauss: usize, refine: Option<(f64, f64)>) -> (f64, f64) {
    let outline = v(&[[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]]);
    let hole = circle(Vec2::new(0.1, 0.0), 0.4, 24);
    let d = Domain::new(
        outline,
        vec![hole],
        vec![("outer".into(), whole(0, 4)), ("hole".into(), whole(1, 24))],
    )
    .unwrap();
    let mut p = params(
        d,
        h,
        gauss,
        Elastic::new(1000.0, 0.25).plane_strain(),
        vec![linear_bc("outer"), linear_bc("hole")],
    );
    if let Some((spacing, width)) = refine {
        p.polygon.as_mut().unwrap().refine.push(Refine {
            segments: whole(1, 24),
            spacing,
            width,
        });
    }
    let mut b = EfgBody::new(&p, [0.0, 0.0]).unwrap();
    b.solve_static().unwrap();
    let e = patch_errors(&b, h);
    println!(
        "holed square patch, h = {h}, gauss = {gauss}, refine {refine:?}: {} nodes, displacement error {:.2e}, interior stress error {:.2e}",
        b.n_nodes(),
        e.0,
        e.1
    );
    e
}

#[test]
fn patch_test_l_shape() {
    // gauss 5: each triangle split in 4, 28 points
    let (eu, es) = l_shape(0.2, 5);
    assert!(eu < 1e-4 && es < 1e-4, "{eu:.2e} {es:.2e}");
    let (eu, es) = l_shape(0.1, 6);
    assert!(eu < 1e-4 && es < 1e-4, "{eu:.2e} {es:.2e}");
}

#[test]
fn patch_test_holed_square() {
    let (eu, es) = holed_square(0.2, 6);
    assert!(eu < 1e-4 && es < 1e-4, "{eu:.2e} {es:.2e}");
}

/// Refinement near edges (graded spacing, supports and integration that
/// follow it) keeps the patch test at the uniform bounds.
#[test]
fn patch_test_refined_l_shape_and_holed_square() {
    let (eu, es) = l_shape_refined(0.2, 5, Some((0.05, 0.2)));
    assert!(eu < 1e-4 && es < 1e-4, "{eu:.2e} {es:.2e}");
    let (eu, es) = holed_square_refined(0.2, 6, Some((0.05, 0.3)));
    assert!(eu < 1e-4 && es < 1e-4, "{eu:.2e} {es:.2e}");
}

#[test]
fn visibility_hides_across_a_slot() {
    use efgdem::efg::support::Support;
    let outline = v(&[[0.0, 0.0], [4.0, 0.0], [4.0, 4.0], [0.0, 4.0]]);
    let slot = v(&[[1.0, 1.95], [3.0, 1.95], [3.0, 2.05], [1.0, 2.05]]);
    let d = Domain::new(outline, vec![slot], vec![]).unwrap();
    let nodes = vec![
        [2.0, 1.8, 0.5, 0.5],
        [2.0, 2.2, 0.5, 0.5],
        [2.3, 1.8, 0.5, 0.5],
    ];
    let (below, above) = (Vec2::new(2.0, 1.85), Vec2::new(2.0, 2.15));
    let plain = Support::new(nodes.clone());
    assert!(plain.covers(0, above) && plain.covers(1, below));
    for diffraction in [false, true] {
        let s = Support::new(nodes.clone()).with_visibility(&d, diffraction);
        assert!(!s.covers(0, above), "node 0 sees across the slot");
        assert!(!s.covers(1, below), "node 1 sees across the slot");
        assert!(s.covers(0, below) && s.covers(2, below) && s.covers(1, above));
    }
    // around the slot's end the diffraction weight bends the distance:
    // node (0.9, 1.9) and the point (1.1, 2.1) see each other only around (1, 2.05)
    let n = vec![[0.8, 1.9, 0.5, 0.5]];
    let p = Vec2::new(1.1, 2.1);
    let vis = Support::new(n.clone()).with_visibility(&d, false);
    let dif = Support::new(n).with_visibility(&d, true);
    assert!(vis.hidden(0, p) && !vis.covers(0, p));
    let (f, _) = dif.diffraction(0, p).unwrap();
    let c = Vec2::new(1.0, 2.05);
    let bent = (c - Vec2::new(0.8, 1.9)).norm() + (p - c).norm();
    assert!(
        (f - bent / (p - Vec2::new(0.8, 1.9)).norm()).abs() < 1e-12,
        "{f}"
    );
    assert!(dif.covers(0, p));
}

/// Points of the arc of radius `r` about the origin from angle `t0` to
/// `t1` (radians), `m` segments, without the first point.
fn arc(r: f64, t0: f64, t1: f64, m: usize) -> Vec<Vec2> {
    (1..=m)
        .map(|k| {
            let t = t0 + (t1 - t0) * k as f64 / m as f64;
            Vec2::new(r * t.cos(), r * t.sin())
        })
        .collect()
}

fn arc_segments(r: f64, h: f64) -> usize {
    // chords of at most h/2: the polygonal hole is within 1e-3 a of the circle
    ((std::f64::consts::FRAC_PI_2 * r / (0.5 * h)).ceil() as usize).max(8)
}

fn fixed_component(edge: &str, c: usize) -> EdgeCondition {
    let z = Some(Prescribed::Value(0.0));
    EdgeCondition {
        ux: if c == 0 { z.clone() } else { None },
        uy: if c == 1 { z } else { None },
        ..EdgeCondition::on(edge)
    }
}

/// Kirsch's quarter plate [0, L]² minus the disc r < a, spacing h:
/// (σ_xx at (0, a) / 3σ, relative energy-norm error, nodes).
fn kirsch(h: f64) -> (f64, f64, usize) {
    kirsch_refined(h, None)
}

/// The Kirsch plate at spacing `h`, with `refine = Some((h_r, width))`
/// nodes at `h_r` along the hole's arc and within `width` of it.
fn kirsch_refined(h: f64, refine: Option<(f64, f64)>) -> (f64, f64, usize) {
    let (a, l, s) = (1.0, 5.0, 1.0);
    let m = arc_segments(a, refine.map_or(h, |r| r.0));
    let mut outline = v(&[[a, 0.0], [l, 0.0], [l, l], [0.0, l], [0.0, a]]);
    outline.extend(
        arc(a, std::f64::consts::FRAC_PI_2, 0.0, m)
            .into_iter()
            .take(m - 1),
    );
    let edges = vec![
        ("bottom".to_string(), vec![(0, 0)]),
        ("outer".to_string(), vec![(0, 1), (0, 2)]),
        ("left".to_string(), vec![(0, 3)]),
    ];
    let d = Domain::new(outline, vec![], edges).unwrap();
    let el = Elastic::new(1000.0, 0.3);
    let bc = vec![
        fixed_component("bottom", 1),
        fixed_component("left", 0),
        EdgeCondition {
            kirsch: Some(KirschSpec { s, a }),
            ..EdgeCondition::on("outer")
        },
    ];
    let mut p = params(d, h, 5, el, bc);
    p.penalty = None;
    if let (Some((hr, width)), Some(poly)) = (refine, p.polygon.as_mut()) {
        poly.refine.push(Refine {
            segments: (4..4 + m).map(|i| (0, i)).collect(),
            spacing: hr,
            width,
        });
    }
    let mut b = EfgBody::new(&p, [0.0, 0.0]).unwrap();
    b.solve_static().unwrap();
    let exact = efgdem::continuum::kirsch::Kirsch::new(s, a);
    // the limit from inside Ω: at a boundary vertex itself the derivatives
    // of the diffracted weights are direction-dependent (cone point)
    let top = b.sample(Vec2::new(0.0, a + 1e-7)).unwrap();
    let err = b.energy_error_polygon(|x| exact.stress(x), 2).unwrap();
    // the displacement against Kirsch's (plane stress κ = (3 − ν)/(1 + ν))
    let mu = 1000.0 / 2.6;
    let ue = exact.displacement(Vec2::new(0.0, a), mu, 2.7 / 1.3);
    println!(
        "Kirsch h = {h}, refine {refine:?}: {} nodes, {} domain Gauss points, σ_xx(0, a)/3σ = {:.5}, u_y(0, a) = {:.5e} (exact {:.5e}), energy-norm error {:.3e}",
        b.n_nodes(),
        b.info.domain_points,
        top.stress[0] / (3.0 * s),
        top.u.y,
        ue[1],
        err
    );
    (top.stress[0] / (3.0 * s), err, b.n_nodes())
}

#[test]
fn kirsch_plate_coarse() {
    let (r1, e1, _) = kirsch(0.4);
    let (r2, e2, _) = kirsch(0.2);
    let rate = (e1 / e2).log2();
    println!("energy-norm rate {rate:.2}");
    assert!(
        (r2 - 1.0).abs() < 0.05,
        "σ_xx(0, a)/3σ = {r2} (h = 0.4: {r1})"
    );
    assert!(e2 < e1 && e2 < 0.05 && rate > 0.7, "{e1} {e2}");
}

/// Refinement near the hole only: the stress concentration within 1 % at
/// an eighth of the uniformly refined node count (h = 0.05: 9 916 nodes,
/// σ_xx(0, a)/3σ = 0.9924, energy-norm error 1.48e-3; measured here 1 200
/// nodes, 0.9926, 2.9e-3, against 1.5e-2 unrefined).
#[test]
fn kirsch_plate_refined_near_the_hole() {
    let (r, e, n) = kirsch_refined(0.2, Some((0.05, 0.5)));
    let (_, e0, n0) = kirsch(0.2);
    println!(
        "refined near the hole: {n} nodes (coarse {n0}), σ_xx(0, a)/3σ = {r:.5}, energy-norm error {e:.3e} (coarse {e0:.3e})"
    );
    assert!((r - 1.0).abs() < 0.01, "σ_xx(0, a)/3σ = {r}");
    assert!(
        n < 1500 && e < 0.25 * e0,
        "{n} nodes, error {e} against {e0}"
    );
}

#[test]
#[ignore = "refined Kirsch plate (~1 min): cargo test --release --test efg_polygon -- --ignored"]
fn kirsch_plate_refined() {
    let mut prev: Option<(f64, f64)> = None;
    let mut last = 0.0;
    for h in [0.4, 0.2, 0.1, 0.05] {
        let (r, e, n) = kirsch(h);
        if let Some((hp, ep)) = prev {
            println!(
                "| {h} | {n} | {r:.5} | {e:.3e} | {:.2} |",
                (ep / e).ln() / (hp / h).ln()
            );
        } else {
            println!("| {h} | {n} | {r:.5} | {e:.3e} | – |");
        }
        prev = Some((h, e));
        last = r;
    }
    assert!((last - 1.0).abs() < 0.01, "σ_xx(0, a)/3σ = {last}");
}

/// Lamé's quarter ring a ≤ r ≤ b under internal pressure p, plane stress:
/// (u_r(a)/exact, σ_θθ(a)/exact).
fn lame(h: f64) -> (f64, f64) {
    let (a, bb, pr, e, nu) = (1.0, 2.0, 1.0, 1000.0, 0.3);
    let (mi, mo) = (arc_segments(a, h), arc_segments(bb, h));
    let half = std::f64::consts::FRAC_PI_2;
    let mut outline = vec![Vec2::new(a, 0.0), Vec2::new(bb, 0.0)];
    outline.extend(arc(bb, 0.0, half, mo));
    outline.push(Vec2::new(0.0, a));
    outline.extend(arc(a, half, 0.0, mi).into_iter().take(mi - 1));
    let n = outline.len();
    let edges = vec![
        ("bottom".to_string(), vec![(0, 0)]),
        ("left".to_string(), vec![(0, mo + 1)]),
        ("inner".to_string(), (mo + 2..n).map(|i| (0, i)).collect()),
    ];
    let d = Domain::new(outline, vec![], edges).unwrap();
    let bc = vec![
        fixed_component("bottom", 1),
        fixed_component("left", 0),
        EdgeCondition {
            pressure: Some(pr),
            ..EdgeCondition::on("inner")
        },
    ];
    let mut p = params(d, h, 5, Elastic::new(e, nu), bc);
    p.penalty = None;
    let mut b = EfgBody::new(&p, [0.0, 0.0]).unwrap();
    b.solve_static().unwrap();
    let ca = pr * a * a / (bb * bb - a * a);
    let cb = ca * bb * bb;
    let ur = ((1.0 - nu) * ca * a + (1.0 + nu) * cb / a) / e;
    let stt = ca + cb / (a * a);
    // limits from inside Ω (see `kirsch`)
    let s0 = b.sample(Vec2::new(a + 1e-7, 0.0)).unwrap();
    let s1 = b.sample(Vec2::new(0.0, a + 1e-7)).unwrap();
    let r = (
        (s0.u.x + s1.u.y) / (2.0 * ur),
        (s0.stress[1] + s1.stress[0]) / (2.0 * stt),
    );
    println!(
        "Lamé h = {h}: {} nodes, u_r(a)/exact = {:.5} ({:.5} at (a, 0), {:.5} at (0, a)), σ_θθ(a)/exact = {:.5} ({:.5}, {:.5})",
        b.n_nodes(),
        r.0,
        s0.u.x / ur,
        s1.u.y / ur,
        r.1,
        s0.stress[1] / stt,
        s1.stress[0] / stt
    );
    r
}

#[test]
fn lame_ring_internal_pressure() {
    let (u, s) = lame(0.1);
    assert!((u - 1.0).abs() < 0.01 && (s - 1.0).abs() < 0.01, "{u} {s}");
}

// ---- scenario files: a polygon body end to end, and located errors ----

#[allow(dead_code)]
mod common;

/// A holed plate with a pressurised hole, through the CLI.
const PLATE: &str = r#"[simulation]
analysis = "static"

[[body]]
name = "plate"
outline = [[0.0, 0.0], [4.0, 0.0], [4.0, 2.0], [0.0, 2.0]]
holes = [{ center = [2.0, 1.0], radius = 0.5, segments = 24 }]
spacing = 0.25
elastic = { E = 1000.0, nu = 0.3 }

[body.edges]
base = { loop = 0, segments = [0, 0] }
wall = { loop = 1 }

[[body.bc]]
edge = "base"
fixed = true

[[body.bc]]
edge = "wall"
pressure = 1.0
"#;

fn cli(tag: &str, text: &str) -> (std::process::Output, std::path::PathBuf, std::path::PathBuf) {
    let d = common::tmpdir(tag);
    let f = d.join("s.toml");
    std::fs::write(&f, text).unwrap();
    let o = common::bin()
        .args(["run", f.to_str().unwrap(), "-o"])
        .arg(d.join("out"))
        .output()
        .unwrap();
    (o, f, d)
}

#[test]
fn polygon_scenario_runs_and_writes_triangles() {
    let (o, _, d) = cli("poly-good", PLATE);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let out = d.join("out");
    let vtu: Vec<_> = std::fs::read_dir(&out)
        .unwrap()
        .flatten()
        .map(|e| e.path())
        .filter(|p| p.extension().is_some_and(|x| x == "vtu"))
        .collect();
    assert!(!vtu.is_empty(), "no .vtu in {out:?}");
    let text = String::from_utf8_lossy(&std::fs::read(&vtu[0]).unwrap()).to_string();
    assert!(text.contains("NumberOfCells"), "{text:.300}");
    std::fs::remove_dir_all(d).unwrap();
}

fn bad(tag: &str, from: &str, to: &str, field: &str, words: &str) {
    assert!(PLATE.contains(from), "{from}");
    let text = PLATE.replacen(from, to, 1);
    let (o, f, d) = cli(tag, &text);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{tag}: {err}");
    assert!(err.contains(&format!("{}:", f.display())), "{tag}: {err}");
    assert!(err.contains(field), "{tag}: expected `{field}` in: {err}");
    assert!(err.contains(words), "{tag}: expected `{words}` in: {err}");
    std::fs::remove_dir_all(d).unwrap();
}

#[test]
fn clockwise_outline_is_refused() {
    bad(
        "poly-cw",
        "[[0.0, 0.0], [4.0, 0.0], [4.0, 2.0], [0.0, 2.0]]",
        "[[0.0, 0.0], [0.0, 2.0], [4.0, 2.0], [4.0, 0.0]]",
        "outline",
        "clockwise",
    );
}

#[test]
fn self_intersecting_outline_is_refused() {
    bad(
        "poly-bow",
        "[[0.0, 0.0], [4.0, 0.0], [4.0, 2.0], [0.0, 2.0]]",
        "[[0.0, 0.0], [4.0, 2.0], [4.0, 0.0], [0.0, 2.0]]",
        "outline",
        "not simple",
    );
}

#[test]
fn hole_outside_is_refused() {
    bad(
        "poly-hole",
        "center = [2.0, 1.0]",
        "center = [5.0, 1.0]",
        "holes",
        "not strictly inside",
    );
}

#[test]
fn unknown_edge_is_refused() {
    bad(
        "poly-edge",
        "edge = \"wall\"",
        "edge = \"wal\"",
        "bc[1].edge",
        "unknown edge `wal`",
    );
}

#[test]
fn bad_refinements_are_refused() {
    let good = "spacing = 0.25\nrefine = [{ edges = [\"wall\"], spacing = 0.1, width = 0.3 }]";
    for (tag, to, field, words) in [
        (
            "poly-refine-edge",
            good.replace("\"wall\"", "\"wal\""),
            "refine[0].edges[0]",
            "unknown edge `wal`",
        ),
        (
            "poly-refine-coarse",
            good.replace("spacing = 0.1", "spacing = 0.25"),
            "refine[0].spacing",
            "below the body's spacing",
        ),
        (
            "poly-refine-zero",
            good.replace("spacing = 0.1", "spacing = 0.0"),
            "refine[0].spacing",
            "must be > 0",
        ),
        (
            "poly-refine-width",
            good.replace("width = 0.3", "width = -1.0"),
            "refine[0].width",
            "must be a finite number > 0",
        ),
    ] {
        bad(tag, "spacing = 0.25", &to, field, words);
    }
}

/// The refinement through a scenario file: more nodes, the run succeeds.
#[test]
fn refined_polygon_scenario_runs() {
    let text = PLATE.replacen(
        "spacing = 0.25",
        "spacing = 0.25\nrefine = [{ edges = [\"wall\"], spacing = 0.0625, width = 0.25 }]",
        1,
    );
    let sc = efgdem::scenario::parse(&text, "refined.toml").unwrap();
    let p = sc.body[0].params();
    let refine = &p.polygon.as_ref().unwrap().refine;
    assert_eq!(refine.len(), 1);
    let mut segs = refine[0].segments.clone();
    segs.sort();
    assert_eq!(segs, whole(1, 24));
    let b = EfgBody::new(&p, [0.0, 0.0]).unwrap();
    let plain = EfgBody::new(
        &efgdem::scenario::parse(PLATE, "plate.toml").unwrap().body[0].params(),
        [0.0, 0.0],
    )
    .unwrap();
    println!(
        "refined plate: {} nodes (plain {})",
        b.n_nodes(),
        plain.n_nodes()
    );
    assert!(b.n_nodes() > plain.n_nodes() + 100);
    let (o, _, d) = cli("poly-refined", &text);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    std::fs::remove_dir_all(d).unwrap();
}

#[test]
fn polygon_on_fem_body_is_refused() {
    bad(
        "poly-fem",
        "name = \"plate\"",
        "name = \"plate\"\nmethod = \"fem-q4\"",
        "outline",
        "EFG only",
    );
}

/// Hash of [`rectangle_shape_functions_are_bitwise_unchanged`] at commit 026963b.
const EXPECTED_HASH: u64 = 0xe7107dfece3ecbde;

/// FNV-1a over the shape-function rows of a rectangular grid at 500
/// pseudo-random points: the constant is the value of the code before
/// polygon bodies (commit 026963b), so rectangles' shape functions are
/// bitwise unchanged by the visibility test.
#[test]
fn rectangle_shape_functions_are_bitwise_unchanged() {
    use efgdem::efg::shape::{ShapeRow, shape_functions};
    use efgdem::efg::support::Support;
    let xs: Vec<f64> = (0..9)
        .map(|i| i as f64 * 0.3 + 0.01 * (i * i) as f64)
        .collect();
    let ys: Vec<f64> = (0..6).map(|j| -1.0 + j as f64 * 0.45).collect();
    let s = Support::for_grid(&xs, &ys, 2.0);
    let mut h: u64 = 0xcbf29ce484222325;
    let mut mix = |v: u64| {
        h ^= v;
        h = h.wrapping_mul(0x100000001b3);
    };
    let mut seed = 7u64;
    let mut rnd = || {
        seed = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (seed >> 11) as f64 / (1u64 << 53) as f64
    };
    let mut row = ShapeRow::new();
    for _ in 0..500 {
        let p = Vec2::new(
            xs[0] + rnd() * (xs[8] - xs[0]),
            ys[0] + rnd() * (ys[5] - ys[0]),
        );
        shape_functions(&s, p, &mut row).unwrap();
        for k in 0..row.len() {
            mix(row.idx[k] as u64);
            mix(row.phi[k].to_bits());
            mix(row.dx[k].to_bits());
            mix(row.dy[k].to_bits());
        }
    }
    println!("shape-function hash {h:#018x}");
    assert_eq!(h, EXPECTED_HASH);
}

/// A disc (r = 0.05, k_n = k_s = 1e6, μ = 0.5) dropped at 1 m/s onto the
/// slanted top edge (slope −0.2) of a stiff polygon wedge rebounds like on
/// a rigid wall along that edge: same contact duration and the same
/// rebound velocity vector (its x component comes from the slanted
/// normal only), within 1 %.
#[test]
fn disc_on_a_slanted_polygon_edge_rebounds_like_on_a_rigid_wall() {
    let head = r#"
[simulation]
dt = 1e-5
steps = 1
gravity = [0.0, 0.0]

[[material]]
name = "disc"
density = 1000.0
kn = 1.0e6
ks = 1.0e6
friction = 0.5

[granular]
material = "disc"
thickness = 1.0
discs = [[0.5, 0.46, 0.05]]
velocity = [0.0, -1.0]
damping = { kind = "none" }
"#;
    let body = r#"
[[body]]
name = "wedge"
outline = [[0.0, 0.0], [1.0, 0.0], [1.0, 0.3], [0.0, 0.5]]
spacing = 0.05
elastic = { E = 2.1e12, nu = 0.3, density = 2000.0, plane = "strain" }
self_weight = false
[body.edges]
base = { loop = 0, segments = [0, 0] }
[[body.bc]]
edge = "base"
fixed = true
"#;
    let wall = "[[wall]]\nname = \"slope\"\nfrom = [1.0, 0.3]\nto = [0.0, 0.5]\n";
    let sc = efgdem::scenario::parse(&format!("{head}{body}"), "wedge.toml").unwrap();
    let mut m = sc.build().unwrap().into_coupled().unwrap();
    let mut steps = 0;
    for _ in 0..3000 {
        m.step().unwrap();
        steps += usize::from(!m.contacts.is_empty());
    }
    let vc = m.granular.particles.vel[0];
    let wsc = efgdem::scenario::parse(&format!("{head}{wall}"), "wall.toml").unwrap();
    let mut g = wsc.build().unwrap().into_granular().unwrap();
    let mut wsteps = 0;
    for _ in 0..3000 {
        g.step();
        wsteps += usize::from(g.walls[0].force.norm() > 0.0);
    }
    let vw = g.particles.vel[0];
    println!(
        "wedge: contact {steps} vs {wsteps} steps, rebound ({:.5}, {:.5}) vs rigid wall ({:.5}, {:.5})",
        vc.x, vc.y, vw.x, vw.y
    );
    // the slanted edge alone as the contact boundary: the same rebound;
    // the base alone: the disc enters the wedge untouched
    for (edges, touches) in [("[\"slope\"]", true), ("[\"base\"]", false)] {
        let named = body.replace(
            "self_weight = false",
            &format!("self_weight = false\ncontact_edges = {edges}"),
        ) + "";
        let named = named.replace(
            "base = { loop = 0, segments = [0, 0] }",
            "base = { loop = 0, segments = [0, 0] }\nslope = { loop = 0, segments = [2, 2] }",
        );
        let sc = efgdem::scenario::parse(&format!("{head}{named}"), "wedge.toml").unwrap();
        let mut m = sc.build().unwrap().into_coupled().unwrap();
        let mut n = 0;
        for _ in 0..3000 {
            m.step().unwrap();
            n += usize::from(!m.contacts.is_empty());
        }
        let v = m.granular.particles.vel[0];
        if touches {
            assert!(
                n == steps && (v - vc).norm() < 1e-9 * vc.norm(),
                "{edges}: {n} {v:?}"
            );
        } else {
            assert!(
                n == 0 && (v - Vec2::new(0.0, -1.0)).norm() < 1e-12,
                "{edges}: {n} {v:?}"
            );
        }
    }
    let bad = body.replace(
        "self_weight = false",
        "self_weight = false\ncontact_edges = [\"slop\"]",
    );
    let e = efgdem::scenario::parse(&format!("{head}{bad}"), "wedge.toml")
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("contact_edges") && e.contains("unknown edge `slop`"),
        "{e}"
    );
    // the rebound leaves along the slanted normal's side: +x
    assert!(vw.x > 0.05 && vw.y > 0.5, "{vw:?}");
    assert!(wsteps > 700 && (steps as f64 - wsteps as f64).abs() < 0.01 * wsteps as f64);
    assert!((vc - vw).norm() < 0.01 * vw.norm(), "{vc:?} vs {vw:?}");
}

/// A disc moving at 1 m/s inside a square hole of a stiff polygon block
/// hits the hole's right edge and rebounds like on a rigid wall there: the
/// hole's contact chain (stored clockwise, body on its left) has its
/// normal pointing into the hole.
#[test]
fn disc_in_a_hole_rebounds_like_on_a_rigid_wall() {
    let head = r#"
[simulation]
dt = 1e-5
steps = 1
gravity = [0.0, 0.0]

[[material]]
name = "disc"
density = 1000.0
kn = 1.0e6
ks = 1.0e6
friction = 0.5

[granular]
material = "disc"
thickness = 1.0
discs = [[0.64, 0.52, 0.05]]
velocity = [1.0, -0.3]
damping = { kind = "none" }
"#;
    let body = r#"
[[body]]
name = "block"
outline = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]]
holes = [[[0.3, 0.3], [0.7, 0.3], [0.7, 0.7], [0.3, 0.7]]]
spacing = 0.05
elastic = { E = 2.1e12, nu = 0.3, density = 2000.0, plane = "strain" }
self_weight = false
[[body.bc]]
edge = "outline"
fixed = true
"#;
    let wall = "[[wall]]\nname = \"hole_right\"\nfrom = [0.7, 0.7]\nto = [0.7, 0.3]\n";
    let sc = efgdem::scenario::parse(&format!("{head}{body}"), "hole.toml").unwrap();
    let mut m = sc.build().unwrap().into_coupled().unwrap();
    let mut steps = 0;
    for _ in 0..2500 {
        m.step().unwrap();
        steps += usize::from(!m.contacts.is_empty());
    }
    let vc = m.granular.particles.vel[0];
    let wsc = efgdem::scenario::parse(&format!("{head}{wall}"), "wall.toml").unwrap();
    let mut g = wsc.build().unwrap().into_granular().unwrap();
    let mut wsteps = 0;
    for _ in 0..2500 {
        g.step();
        wsteps += usize::from(g.walls[0].force.norm() > 0.0);
    }
    let vw = g.particles.vel[0];
    println!(
        "hole: contact {steps} vs {wsteps} steps, rebound ({:.5}, {:.5}) vs rigid wall ({:.5}, {:.5})",
        vc.x, vc.y, vw.x, vw.y
    );
    assert!(vw.x < -0.5, "{vw:?}");
    assert!(wsteps > 700 && (steps as f64 - wsteps as f64).abs() < 0.01 * wsteps as f64);
    assert!((vc - vw).norm() < 0.01 * vw.norm(), "{vc:?} vs {vw:?}");
}

/// The static limit in a re-entrant corner: a disc (m = 7.854 kg) placed
/// in the inner corner of an L-shaped polygon body, against its vertical
/// step and on its horizontal one, under gravity, settles (contact
/// dashpots, body damping) with the contact forces on it summing to
/// `(0, m g)` within 1e-3 of m g.
#[test]
fn disc_resting_in_a_re_entrant_corner_carries_its_weight() {
    let r: f64 = 0.05;
    let kn = 1.0e6;
    let m = 1000.0 * std::f64::consts::PI * r * r;
    let g = 9.81;
    let y = 0.3 + r - m * g / kn;
    let src = format!(
        r#"
[simulation]
dt = 1e-5
steps = 1
gravity = [0.0, -{g}]

[[material]]
name = "disc"
density = 1000.0
kn = {kn}
ks = 1.0e6
friction = 0.3

[granular]
material = "disc"
thickness = 1.0
discs = [[0.55, {y}, {r}]]
damping = {{ kind = "critical-ratio", zeta = 0.7 }}
allow_overlap = true

[[body]]
name = "step"
outline = [[0.0, 0.0], [1.0, 0.0], [1.0, 0.3], [0.5, 0.3], [0.5, 0.6], [0.0, 0.6]]
spacing = 0.05
elastic = {{ E = 1.0e9, nu = 0.3, density = 2000.0, plane = "strain" }}
damping = 2.0e6
self_weight = false
[body.edges]
base = {{ loop = 0, segments = [0, 0] }}
[[body.bc]]
edge = "base"
fixed = true
"#
    );
    let sc = efgdem::scenario::parse(&src, "corner.toml").unwrap();
    let mut model = sc.build().unwrap().into_coupled().unwrap();
    for _ in 0..20000 {
        model.step().unwrap();
    }
    let f = model.contacts.iter().fold(Vec2::ZERO, |a, c| a + c.force);
    let w = m * g;
    println!(
        "corner: {} contacts, force on the disc ({:.6}, {:.6}) N, m g = {w:.6} N, disc velocity {:?}",
        model.contacts.len(),
        f.x,
        f.y,
        model.granular.particles.vel[0]
    );
    assert!(!model.contacts.is_empty());
    assert!(
        (f.y - w).abs() < 1e-3 * w && f.x.abs() < 1e-3 * w,
        "{f:?} vs {w}"
    );
}
