//! The growth path of `examples/crack_path.toml` against Cotterell &
//! Rice's analytical path: runs the scenario's static growth through the
//! library, prints the path and its distance to the analytical one, and
//! draws `crack_path.png` (computed, analytical, and the straight path of
//! the same field without T-stress):
//!
//!     cargo run --release --example crack_path -- [SCENARIO] [-o out/crack_path]

use efgdem::continuum::crack_tip::{cotterell_rice_path, max_hoop_stress};
use efgdem::efg::EfgBody;
use efgdem::output::plot::{Chart, Mark, Series, line_chart};
use std::path::{Path, PathBuf};

fn main() {
    if let Err(e) = main_() {
        eprintln!("error: {e}");
        std::process::exit(2);
    }
}

fn main_() -> Result<(), String> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let file = args
        .first()
        .filter(|a| !a.starts_with('-'))
        .cloned()
        .unwrap_or("examples/crack_path.toml".into());
    let out = args
        .iter()
        .position(|a| a == "-o")
        .and_then(|i| args.get(i + 1))
        .map_or(PathBuf::from("out/crack_path"), PathBuf::from);
    let sc = efgdem::scenario::load(Path::new(&file)).map_err(|e| e.to_string())?;
    let p = sc.body[0].params();
    let w =
        p.bc.iter()
            .find_map(|b| b.williams)
            .ok_or("the scenario has no `williams` boundary condition")?;
    let mut b = EfgBody::new(&p, sc.simulation.gravity).map_err(|e| e.to_string())?;
    b.solve_static_growing().map_err(|e| e.to_string())?;
    let k = [w.k1, w.k2];
    let path: Vec<(f64, f64)> = b.cracks()[0]
        .crack
        .points
        .iter()
        .filter(|q| q.x >= 0.0)
        .map(|q| (q.x, q.y))
        .collect();
    println!("     x (m)      y (m)  analytical (m)  difference (m)");
    for &(x, y) in &path {
        let r = cotterell_rice_path(k, w.t, x);
        println!("{x:10.4} {y:10.5} {r:15.5} {:15.5}", y - r);
    }
    let x_end = path.last().map_or(0.0, |q| q.0);
    let curve = |t: f64| -> Vec<(f64, f64)> {
        (0..=100)
            .map(|i| {
                let x = x_end * i as f64 / 100.0;
                (x, cotterell_rice_path(k, t, x))
            })
            .collect()
    };
    let kink = max_hoop_stress(k).0.to_degrees();
    let chart = Chart {
        title: "Crack path: K_I, K_II and T-stress (Cotterell & Rice 1980)".into(),
        x_label: "x ahead of the initial tip (m)".into(),
        y_label: "y (m)".into(),
        series: vec![
            Series::paper("Cotterell & Rice, first order", curve(w.t), Mark::Dashed),
            Series::new("same K, T = 0 (straight)", curve(0.0), Mark::Dashed)
                .with_color(efgdem::output::plot::REFERENCE_COLOR),
            Series::new("efgdem (tips after each increment)", path, Mark::Points),
        ],
        notes: vec![
            format!(
                "K_II/K_I = {:.3}: first kink {kink:.2}° (maximum hoop stress)",
                w.k2 / w.k1
            ),
            format!("T = {:.3e} Pa, K_I = {:.3e} Pa·√m", w.t, w.k1),
        ],
        ..Chart::default()
    };
    std::fs::create_dir_all(&out).map_err(|e| e.to_string())?;
    line_chart(&out.join("crack_path.png"), &chart, 1000, 500).map_err(|e| e.to_string())?;
    println!("wrote {}", out.join("crack_path.png").display());
    Ok(())
}
