//! The energy account of a body driven by a moving penalty edge (ERRATA
//! E4): the strain energy is `½UᵀKU` alone, the penalty springs' energy is
//! taken from their gap, and the moving edge's work is consistent with it,
//! so a footing driven through free space dissipates nothing.

use efgdem::scenario::parse;

/// A steel footing 1 × 0.5 (11 × 6 nodes, γ = ½, β = ¼, undamped, default
/// penalty α = 10⁵E) whose top edge is driven down at 1 m/s for 0.2 s
/// (0.2 m, 40 % of its height) through free space; one disc far away.
const FOOTING: &str = r#"
[simulation]
dt = 1.0e-4
steps = 2000
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
discs = [[10.0, 10.0, 0.05]]

[[body]]
name = "footing"
METHOD
rectangle = { origin = [0.0, 0.0], size = [1.0, 0.5] }
nodes = [11, 6]
elastic = { E = 2.1e11, nu = 0.3, density = 7800.0, thickness = 1.0, plane = "strain" }
newmark = { gamma = 0.5, beta = 0.25 }
[[body.bc]]
edge = "top"
uy = { velocity = -1.0 }

[[probe]]
name = "centre_uy"
point = [0.5, 0.25]
quantity = "uy"

[output]
every = 10
"#;

/// Validation 4: `E_diss` stays below 1e-6 of the largest work done on the
/// footing over the run (EFG: penalty edge; FE: the edge nodes imposed
/// exactly), while the footing moves 0.2 m and vibrates.
#[test]
fn footing_driven_through_free_space_dissipates_nothing() {
    for method in ["", r#"method = "fem-q4""#] {
        let dir = std::env::temp_dir().join(format!(
            "efgdem-footing-{}-{}",
            method.len(),
            std::process::id()
        ));
        let sc = parse(&FOOTING.replace("METHOD", method), "footing.toml").unwrap();
        let opts = efgdem::run::RunOptions {
            quiet: true,
            overwrite: true,
            ..efgdem::run::RunOptions::new(&dir)
        };
        efgdem::run::run(&sc, &opts).unwrap();
        let (cols, rows) = efgdem::output::csv::read(&dir.join("history.csv")).unwrap();
        let col = |n: &str| cols.iter().position(|c| c == n).unwrap();
        let max = |c: usize| rows.iter().map(|r| r[c].abs()).fold(0.0, f64::max);
        let (work, diss) = (max(col("W_ext")), max(col("E_diss")));
        let last = rows.last().unwrap();
        eprintln!(
            "{method:>18}: max W_ext {work:.4e} J, max |E_diss| {diss:.3e} J ({:.2e}), max E_strain {:.3e}, max E_penalty {:.3e}, centre u_y {:.4}",
            diss / work,
            max(col("E_strain")),
            max(col("E_penalty")),
            last[col("centre_uy")]
        );
        // it moved with the edge, and vibrates (strain energy well above 0)
        assert!((last[col("centre_uy")] + 0.2).abs() < 1e-3);
        assert!(max(col("E_strain")) > 0.05 * work);
        assert!(work > 1000.0);
        assert!(diss <= 1e-6 * work, "E_diss {diss} of W_ext {work}");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
