//! Contact edges: by default a body's whole boundary takes part in
//! contacts; a disc that enters a body through an edge left out of
//! `contact_edges` is reported once on stderr.

#[allow(dead_code)]
mod common;
use common::{run_with, summary, tmpdir};

/// A disc (r = 0.05, m = 7.85, k_n = 1e6) thrown at 2 m/s against the left
/// edge of a block 1 × 0.5 (bottom fixed, no gravity); `edges` is the
/// block's `contact_edges` line (empty: the default).
fn scenario(edges: &str) -> String {
    format!(
        r#"
[simulation]
dt = 1.0e-4
steps = 3000
gravity = [0.0, 0.0]

[[material]]
name = "disc"
density = 1000.0
kn = 1.0e6
ks = 1.0e6
friction = 0.3

[granular]
material = "disc"
thickness = 1.0
discs = [[-0.2003, 0.25, 0.05]]
velocity = [2.0, 0.0]

[[body]]
name = "block"
rectangle = {{ origin = [0.0, 0.0], size = [1.0, 0.5] }}
nodes = [11, 6]
elastic = {{ E = 1.0e8, nu = 0.3, density = 2000.0, thickness = 1.0, plane = "strain" }}
{edges}
[[body.bc]]
edge = "bottom"
fixed = true

[[probe]]
name = "disc_x"
disc = 1
quantity = "x"

[[probe]]
name = "disc_vx"
disc = 1
quantity = "vx"

[output]
every = 1
"#
    )
}

/// Run `scenario(edges)`; returns stderr and the history columns.
fn run(tag: &str, edges: &str) -> (String, Vec<String>, Vec<Vec<f64>>) {
    let root = tmpdir(tag);
    let file = root.join("s.toml");
    std::fs::write(&file, scenario(edges)).unwrap();
    let dir = root.join("out");
    let out = run_with(&file, &dir, &[]);
    let stderr = String::from_utf8_lossy(&out.stderr).to_string();
    assert!(out.status.success(), "{stderr}");
    let (cols, rows) = efgdem::output::csv::read(&dir.join("history.csv")).unwrap();
    let entered = summary(&dir)["discs_entered_through_non_contact_edges"]
        .as_u64()
        .unwrap();
    assert_eq!(entered as usize, stderr.matches("warning: disc").count());
    std::fs::remove_dir_all(&dir).unwrap();
    (stderr, cols, rows)
}

/// Validation 5: with the default contact edges the disc is stopped by the
/// block's left edge (which the scenario does not list) and rebounds, the
/// contact force staying below k_n r; with `contact_edges = ["bottom"]` it
/// passes into the block unseen and the warning fires exactly once.
#[test]
fn default_edges_stop_a_disc_and_a_non_contact_edge_is_reported_once() {
    let (err, cols, rows) = run("edges-default", "");
    let col = |n: &str| cols.iter().position(|c| c == n).unwrap();
    let peak = rows
        .iter()
        .map(|r| r[col("contact_fn")])
        .fold(0.0, f64::max);
    let x_max = rows
        .iter()
        .map(|r| r[col("disc_x")])
        .fold(f64::MIN, f64::max);
    let last = rows.last().unwrap();
    eprintln!(
        "default edges: peak contact force {peak:.1} N (k_n r = 5e4), closest centre x = {x_max:.4}, final vx {:.3}",
        last[col("disc_vx")]
    );
    assert!(peak > 1000.0, "the disc must hit the block ({peak} N)");
    assert!(peak < 1.0e6 * 0.05);
    assert!(x_max < 0.0, "the centre never enters the block");
    assert!(last[col("disc_vx")] < -1.5, "the disc rebounds");
    assert!(!err.contains("warning: disc"), "{err}");

    let (err, cols, rows) = run("edges-bottom", r#"contact_edges = ["bottom"]"#);
    let col = |n: &str| cols.iter().position(|c| c == n).unwrap();
    let x_end = rows.last().unwrap()[col("disc_x")];
    eprintln!("{err}");
    assert!(x_end > 0.3, "the disc passes the left edge ({x_end})");
    assert!(rows.iter().all(|r| r[col("contact_fn")] == 0.0));
    assert_eq!(err.matches("warning: disc").count(), 1, "{err}");
    assert!(
        err.contains("warning: disc 1 entered body `block` through a non-contact edge (left) at t = 0.100200 s (step 1002)"),
        "{err}"
    );
}

/// The default is one closed chain around the body; `[]` is none; a list
/// restricts it.
#[test]
fn contact_edges_default_to_one_closed_chain_and_can_be_empty() {
    let chains = |edges: &str| {
        let sc = efgdem::scenario::parse(&scenario(edges), "s.toml").unwrap();
        let m = sc.build().unwrap().into_coupled().unwrap();
        m.bodies[0]
            .contact_boundary()
            .iter()
            .map(|c| (c.segments(), c.reference.first() == c.reference.last()))
            .collect::<Vec<_>>()
    };
    // 11 × 6 nodes, 4 boundary points per node spacing: 4 · (2·10 + 2·5)
    assert_eq!(chains(""), vec![(120, true)]);
    assert_eq!(chains("contact_edges = []"), vec![]);
    assert_eq!(chains(r#"contact_edges = ["bottom"]"#), vec![(40, false)]);
}

/// The entry warning on a polygon body: the block of [`scenario`] as a
/// polygon with a square hole; disc 1 is thrown at its left edge as
/// before, disc 2 (r = 0.03) moves at 2 m/s inside the hole towards the
/// hole's right side. With `contact_edges = ["bottom"]` both pass into the
/// material and each is reported once, under the edge it crossed (`left`,
/// `hole1`); with the default (every loop) neither enters nor is reported.
#[test]
fn polygon_body_reports_discs_entering_through_non_contact_edges() {
    let polygon = |edges: &str| {
        scenario(edges)
            .replace(
                "rectangle = { origin = [0.0, 0.0], size = [1.0, 0.5] }\nnodes = [11, 6]",
                "outline = [[0.0, 0.0], [1.0, 0.0], [1.0, 0.5], [0.0, 0.5]]\nholes = [[[0.5, 0.1], [0.8, 0.1], [0.8, 0.4], [0.5, 0.4]]]\nspacing = 0.05",
            )
            .replace(
                "[[body.bc]]\nedge = \"bottom\"",
                "[body.edges]\nbottom = { loop = 0, segments = [0, 0] }\nleft = { loop = 0, segments = [3, 3] }\n\n[[body.bc]]\nedge = \"bottom\"",
            )
            .replace(
                "discs = [[-0.2003, 0.25, 0.05]]\nvelocity = [2.0, 0.0]",
                "discs = [[-0.2003, 0.25, 0.05], [0.6, 0.25, 0.03]]\nvelocity = [2.0, 0.0]",
            )
    };
    let run_polygon = |tag: &str, edges: &str| {
        let root = tmpdir(tag);
        let file = root.join("s.toml");
        let text = polygon(edges);
        assert!(
            text.contains("holes =") && text.contains("[0.6, 0.25, 0.03]"),
            "{text}"
        );
        std::fs::write(&file, text).unwrap();
        let dir = root.join("out");
        let out = run_with(&file, &dir, &[]);
        let stderr = String::from_utf8_lossy(&out.stderr).to_string();
        assert!(out.status.success(), "{stderr}");
        let entered = summary(&dir)["discs_entered_through_non_contact_edges"]
            .as_u64()
            .unwrap();
        std::fs::remove_dir_all(&root).unwrap();
        (stderr, entered)
    };
    let (err, entered) = run_polygon("edges-polygon-default", "");
    assert!(!err.contains("warning: disc") && entered == 0, "{err}");
    let (err, entered) = run_polygon("edges-polygon-bottom", r#"contact_edges = ["bottom"]"#);
    eprintln!("{err}");
    assert_eq!(entered, 2, "{err}");
    assert_eq!(err.matches("warning: disc").count(), 2, "{err}");
    // disc 2 reaches the hole's side x = 0.8 at t = (0.8 − 0.6)/2 = 0.1 s
    // (step 1000 puts it there up to rounding, on the body's side), disc 1
    // the outline's x = 0 at t = 0.2003/2 = 0.10015 s: each is reported at
    // the first output step with its centre inside
    assert!(
        err.contains("warning: disc 2 entered body `block` through a non-contact edge (hole1) at t = 0.100000 s (step 1000)"),
        "{err}"
    );
    assert!(
        err.contains("warning: disc 1 entered body `block` through a non-contact edge (left) at t = 0.100200 s (step 1002)"),
        "{err}"
    );
}
