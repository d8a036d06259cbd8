//! One set of conventions across the files (docs/reference/conventions.md):
//! a disc has the same number in the scenario's probes, `history.csv`,
//! `discs_final.csv` (`id`) and the frames (`id`, the `GlobalIds`); the
//! frames' contacts give the other disc, wall or body by its number from 1;
//! `center` and `centre` are one field; a rectangle written as
//! `{ origin, size }` or as its corners is the same region everywhere, and
//! a pair of corners the wrong way round is refused with its line.

#[allow(dead_code)]
mod common;
use common::{bin, run, tmpdir};
use efgdem::scenario;

/// The values of the ASCII `DataArray` named `name` in a VTK XML file.
fn array(xml: &str, name: &str) -> Vec<f64> {
    let tag = format!("Name=\"{name}\"");
    let start = xml.find(&tag).unwrap_or_else(|| panic!("no array {name}"));
    let body = &xml[start..];
    let body = &body[body.find('>').unwrap() + 1..body.find("</DataArray>").unwrap()];
    body.split_whitespace()
        .map(|v| v.parse().unwrap())
        .collect()
}

/// 300 discs settling on a floor: slots are renumbered in space-filling
/// order while they move, scenario numbers must not be.
const PACKING: &str = r#"
[simulation]
steps = 3000
gravity = [0.0, -9.81]

[[material]]
name = "sand"
density = 2650.0
kn = 1.0e6
ks = 5.0e5
friction = 0.5

[granular]
material = "sand"
discs = { generate = "hex", box = [[0.0, 0.0], [0.1, 0.2]], radius = [0.003, 0.004], count = 300, jitter = 0.8, seed = 5 }
damping = { kind = "critical-ratio", zeta = 0.3 }

[[wall]]
name = "floor"
from = [0.0, 0.0]
to = [0.1, 0.0]

[[wall]]
name = "left"
from = [0.0, 0.0]
to = [0.0, 0.3]

[[wall]]
name = "right"
from = [0.1, 0.0]
to = [0.1, 0.3]

[[probe]]
name = "x1"
disc = 1
quantity = "x"

[[probe]]
name = "y150"
disc = 150
quantity = "y"

[[probe]]
name = "x300"
disc = 300
quantity = "x"

[output]
every = 1000
vtk_every = 3000
vtk_format = "ascii"
"#;

#[test]
fn a_disc_has_one_number_in_every_file() {
    let root = tmpdir("conventions-ids");
    let file = root.join("packing.toml");
    std::fs::write(&file, PACKING).unwrap();
    let out = root.join("out");
    run(&file, &out);
    // history.csv: the probes' last row
    let (h, rows) = efgdem::output::csv::read(&out.join("history.csv")).unwrap();
    let last = rows.last().unwrap();
    let probe = |n: &str| last[h.iter().position(|c| c == n).unwrap()];
    // discs_final.csv: x,y,r,id
    let text = std::fs::read_to_string(out.join("discs_final.csv")).unwrap();
    let mut lines = text.lines();
    assert_eq!(lines.next(), Some("x,y,r,id"));
    let final_rows: Vec<Vec<f64>> = lines
        .map(|l| l.split(',').map(|v| v.parse().unwrap()).collect())
        .collect();
    let by_id = |id: usize| {
        let r = final_rows.iter().find(|r| r[3] == id as f64).unwrap();
        (r[0], r[1])
    };
    // the last frame: points with their `id`, the GlobalIds
    let vtp = std::fs::read_to_string(out.join("frames/discs_0003000.vtp")).unwrap();
    assert!(vtp.contains("GlobalIds=\"id\""));
    let (ids, pts) = (array(&vtp, "id"), array(&vtp, "Points"));
    let frame = |id: usize| {
        let k = ids.iter().position(|&i| i == id as f64).unwrap();
        (pts[3 * k], pts[3 * k + 1])
    };
    assert_eq!(ids.len(), 300);
    for (id, x, y) in [(1, "x1", ""), (150, "", "y150"), (300, "x300", "")] {
        let (fx, fy) = by_id(id);
        let (vx, vy) = frame(id);
        if !x.is_empty() {
            assert_eq!((probe(x), vx), (fx, fx), "disc {id}: x");
        }
        if !y.is_empty() {
            assert_eq!((probe(y), vy), (fy, fy), "disc {id}: y");
        }
    }
    // the Rust API: the same packing, stepped as far, index = id − 1
    let sc = scenario::load(&file).unwrap();
    let mut model = sc.build().unwrap();
    while model.step < model.steps {
        model.step().unwrap();
    }
    let g = model.granular().unwrap();
    // slot order is not scenario order (else this test could not fail)
    assert!(
        g.particles
            .id
            .iter()
            .enumerate()
            .any(|(k, &i)| k as u32 != i)
    );
    for id in [1, 150, 300] {
        let slot = g.particles.slot[id - 1] as usize;
        let p = g.particles.pos[slot];
        assert_eq!((p.x, p.y), by_id(id), "disc {id} in the Rust API");
    }
    std::fs::remove_dir_all(root).unwrap();
}

/// Discs 1 and 2 on the floor (the second wall), disc 3 on both.
const STACK: &str = r#"
[simulation]
steps = 3000
gravity = [0.0, -9.81]

[[material]]
name = "sand"
density = 2650.0
kn = 1.0e6
ks = 5.0e5
friction = 0.5

[granular]
material = "sand"
discs = [[0.01, 0.0099, 0.01], [0.03, 0.0099, 0.01], [0.02, 0.03, 0.01]]
damping = { kind = "critical-ratio", zeta = 0.7 }
allow_overlap = true

[[wall]]
name = "left"
from = [-0.001, 0.0]
to = [-0.001, 0.1]

[[wall]]
name = "floor"
from = [-0.01, 0.0]
to = [0.05, 0.0]

[output]
vtk_every = 3000
vtk_format = "ascii"
"#;

#[test]
fn contacts_name_discs_and_walls_by_their_numbers() {
    let root = tmpdir("conventions-other");
    let file = root.join("stack.toml");
    std::fs::write(&file, STACK).unwrap();
    let out = root.join("out");
    run(&file, &out);
    let c = std::fs::read_to_string(out.join("frames/contacts_0003000.vtp")).unwrap();
    let (kind, disc, other) = (array(&c, "kind"), array(&c, "disc"), array(&c, "other"));
    let mut seen: Vec<(i64, i64, i64)> = (0..kind.len())
        .map(|k| (kind[k] as i64, disc[k] as i64, other[k] as i64))
        .collect();
    seen.sort();
    // disc–disc: 1–3 and 2–3; disc–wall: discs 1 and 2 on wall 2 (the floor)
    assert_eq!(seen, vec![(0, 1, 3), (0, 2, 3), (1, 1, 2), (1, 2, 2)]);
    let w = std::fs::read_to_string(out.join("frames/walls_0003000.vtp")).unwrap();
    assert_eq!(array(&w, "wall"), vec![1.0, 2.0]);
    std::fs::remove_dir_all(root).unwrap();
}

const POLYGON: &str = r#"
[simulation]
analysis = "static"

[[body]]
name = "plate"
outline = [[0.0, 0.0], [4.0, 0.0], [4.0, 2.0], [0.0, 2.0]]
holes = [{ CENTRE = [2.0, 1.0], radius = 0.5, segments = 24 }]
spacing = 0.25
elastic = { E = 1000.0, nu = 0.3 }

[[body.bc]]
edge = "outline"
fixed = true
"#;

const MEASURE: &str = r#"
[simulation]
steps = 1

[[material]]
name = "m"
density = 1000.0
kn = 1.0e6

[granular]
material = "m"
discs = { generate = "hex", box = BOX, radius = 0.01 }

[[measure]]
name = "a"
REGION

[[measure]]
name = "c"
CENTRE = [0.1, 0.1]
radius = 0.05
"#;

const BODY: &str = r#"
[simulation]
analysis = "static"

[[body]]
name = "beam"
rectangle = RECT
nodes = [9, 3]
elastic = { E = 1000.0, nu = 0.3 }

[[body.bc]]
edge = "left"
fixed = true
"#;

#[test]
fn center_and_centre_are_one_field() {
    for (text, what) in [(POLYGON, "hole"), (MEASURE, "measure")] {
        let text = text
            .replace("BOX", "[[0.0, 0.0], [0.2, 0.2]]")
            .replace("REGION", "rectangle = [[0.0, 0.0], [0.1, 0.1]]");
        let a = scenario::parse(&text.replace("CENTRE", "center"), "a.toml").unwrap();
        let b = scenario::parse(&text.replace("CENTRE", "centre"), "b.toml").unwrap();
        match what {
            "hole" => assert_eq!(
                format!("{:?}", a.body[0].domain().unwrap()),
                format!("{:?}", b.body[0].domain().unwrap())
            ),
            _ => assert_eq!(
                format!("{:?}", a.measure[1].region()),
                format!("{:?}", b.measure[1].region())
            ),
        }
        // both at once: refused
        let both = text.replace("CENTRE = [", "center = [0.1, 0.1]\ncentre = [");
        assert!(scenario::parse(&both, "c.toml").is_err(), "{what}");
    }
    // the built plate is the same
    let nodes = |t: &str| {
        let sc = scenario::parse(&POLYGON.replace("CENTRE", t), "p.toml").unwrap();
        sc.build().unwrap().body(0).n_nodes()
    };
    assert_eq!(nodes("center"), nodes("centre"));
}

#[test]
fn both_rectangle_forms_are_the_same_region_everywhere() {
    // exact in binary, so that origin + size is the upper corner exactly
    let (corners, origin_size) = (
        "[[0.5, -0.25], [4.5, 0.75]]",
        "{ origin = [0.5, -0.25], size = [4.0, 1.0] }",
    );
    let body = |r: &str| scenario::parse(&BODY.replace("RECT", r), "b.toml").unwrap();
    let (a, b) = (body(corners), body(origin_size));
    assert_eq!(a.body[0].rectangle, b.body[0].rectangle);
    let solve = |sc: &scenario::Scenario| {
        let mut m = sc.build().unwrap();
        m.solve_static().unwrap();
        m.body(0).n_nodes()
    };
    assert_eq!(solve(&a), solve(&b));
    let measure = |bx: &str, region: &str| {
        let t = MEASURE
            .replace("BOX", bx)
            .replace("REGION", &format!("rectangle = {region}"))
            .replace("CENTRE", "centre");
        scenario::parse(&t, "m.toml").unwrap()
    };
    let (c, d) = (
        measure("[[0.0, 0.0], [0.25, 0.25]]", corners),
        measure("{ origin = [0.0, 0.0], size = [0.25, 0.25] }", origin_size),
    );
    assert_eq!(c.measure[0].rectangle, d.measure[0].rectangle);
    assert_eq!(
        format!("{:?}", c.granular.as_ref().unwrap().discs),
        format!("{:?}", d.granular.as_ref().unwrap().discs)
    );
    let n = |sc: &scenario::Scenario| sc.build().unwrap().granular().unwrap().particles.len();
    assert_eq!(n(&c), n(&d));
}

#[test]
fn a_pair_of_corners_the_wrong_way_round_is_refused_at_its_line() {
    // what an origin and a size written as a pair used to be read as
    let root = tmpdir("conventions-rect");
    let file = root.join("beam.toml");
    std::fs::write(&file, BODY.replace("RECT", "[[0.65, 0.54], [0.3, 0.1]]")).unwrap();
    let o = bin()
        .args(["check", file.to_str().unwrap()])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("beam.toml:7:"), "{err}");
    assert!(err.contains("x1 > x0 and y1 > y0"), "{err}");
    std::fs::remove_dir_all(root).unwrap();
}
