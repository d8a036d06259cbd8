//! `efgdem view`: writes OUT/view.py with the options given as its
//! defaults; without a display it does not start ParaView's GUI (which
//! aborts in Qt) but says how to render an image; bad options are refused.
//! The rendering itself (`--screenshot`, on a virtual display) is tested
//! with ParaView in python/tests/test_vtk_files.py.

#[allow(dead_code)]
mod common;
use common::{bin, run, tmpdir};

const DISCS: &str = r#"
[simulation]
steps = 20
gravity = [0.0, -9.81]

[[material]]
name = "m"
density = 1000.0
kn = 1.0e5

[granular]
material = "m"
discs = [[0.0, 0.1, 0.01], [0.05, 0.1, 0.01]]

[output]
vtk_every = 10
"#;

fn view(out: &std::path::Path, args: &[&str]) -> std::process::Output {
    bin()
        .arg("view")
        .arg(out)
        .args(args)
        .env_remove("DISPLAY")
        .env_remove("WAYLAND_DISPLAY")
        .output()
        .unwrap()
}

#[test]
fn without_a_display_the_gui_is_not_started_and_the_hint_comes_first() {
    let root = tmpdir("view-cli");
    let file = root.join("discs.toml");
    std::fs::write(&file, DISCS).unwrap();
    let out = root.join("out");
    run(&file, &out);
    let o = view(&out, &[]);
    let (stdout, stderr) = (
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr),
    );
    assert_eq!(o.status.code(), Some(1), "{stderr}");
    assert!(stdout.contains("view.py"), "{stdout}");
    assert!(stderr.contains("no display"), "{stderr}");
    assert!(stderr.contains("--screenshot"), "{stderr}");
    // no ParaView was started: no Qt message
    assert!(!stderr.contains("qt.qpa"), "{stderr}");
    // --no-open: only the script, whose defaults are the options given
    let o = view(
        &out,
        &[
            "--no-open",
            "--range",
            "frame",
            "--warp",
            "20",
            "--region",
            "-0.1",
            "0",
            "0.1",
            "0.2",
        ],
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let script = std::fs::read_to_string(out.join("view.py")).unwrap();
    for s in [
        r#""range":"frame""#,
        r#""warp":20.0"#,
        r#""region":[-0.1,0.0,0.1,0.2]"#,
        r#""percentile":99.0"#,
        r#""edges":"auto""#,
    ] {
        assert!(script.contains(s), "{s} not in the script's defaults");
    }
    assert!(!script.contains("@OPTIONS@") && !script.contains("@DIR@"));
    // bad options
    for (args, what) in [
        (&["--region", "1", "0", "0", "1"][..], "--region"),
        (&["--warp", "0"][..], "--warp"),
        (&["--percentile", "0"][..], "--percentile"),
        (&["--range", "all"][..], "--range"),
        (&["--edges", "maybe"][..], "--edges"),
    ] {
        let o = view(&out, &[&["--no-open"], args].concat());
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success(), "{args:?}");
        assert!(err.contains(what), "{args:?}: {err}");
    }
    std::fs::remove_dir_all(root).unwrap();
}
