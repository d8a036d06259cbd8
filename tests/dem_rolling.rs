//! Rolling resistance (issue 13, §2) and the bitwise guarantee that
//! `rolling_friction = 0` (with `slip_normal = "elastic"` where a dashpot
//! makes the two Coulomb caps differ) is the code before issue 13.

use efgdem::scenario;

/// FNV-1a over the bits of the values.
#[derive(Clone, Copy)]
struct Hash(u64);

impl Hash {
    fn new() -> Self {
        Hash(0xcbf2_9ce4_8422_2325)
    }
    fn f(&mut self, x: f64) {
        for b in x.to_bits().to_le_bytes() {
            self.0 ^= u64::from(b);
            self.0 = self.0.wrapping_mul(0x0100_0000_01b3);
        }
    }
}

/// `src` with `extra` lines inserted after every `cohesion = ` line of a
/// `[[material]]`.
fn with_fields(src: &str, extra: &str) -> String {
    let mut out = String::new();
    for l in src.lines() {
        out.push_str(l);
        out.push('\n');
        if l.starts_with("cohesion =") && !extra.is_empty() {
            out.push_str(extra);
            out.push('\n');
        }
    }
    out
}

/// A loose random packing under gravity with a piston, two materials,
/// friction and cohesion; `damping` is the `[granular]` damping line.
fn packing(damping: &str) -> String {
    format!(
        r#"
[simulation]
dt = 1e-3
steps = 3000
gravity = [0.0, -9.81]

[[material]]
name = "grain"
density = 1.0
kn = 1.0e5
ks = 0.8e5
friction = 0.5
cohesion = 0.05

[[material]]
name = "steel"
density = 1.0
kn = 2.0e5
ks = 1.0e5
friction = 0.3
cohesion = 0.0

[granular]
material = "grain"
discs = {{ generate = "random", box = [[0.0, 0.0], [60.0, 50.0]], radius = [0.8, 1.2], count = 400, seed = 5, method = "loose" }}
damping = {damping}

[[wall]]
name = "floor"
from = [0.0, 0.0]
to = [60.0, 0.0]
material = "steel"

[[wall]]
name = "left"
from = [0.0, 0.0]
to = [0.0, 80.0]

[[wall]]
name = "right"
from = [60.0, 0.0]
to = [60.0, 80.0]
material = "steel"

[[wall]]
name = "piston"
from = [0.0, 51.0]
to = [60.0, 51.0]
velocity = [0.3, -4.0]
"#
    )
}

/// Hash of a granular run: disc states by scenario id every 50 steps,
/// and the wall forces.
fn dem_hash(src: &str) -> u64 {
    let sc = scenario::parse(src, "t.toml").expect("valid scenario");
    let mut g = efgdem::dem::build::build(&sc).expect("builds");
    let steps = efgdem::dem::build::steps(&sc, g.dt);
    let mut h = Hash::new();
    for s in 0..steps {
        g.step();
        if s % 50 == 49 || s + 1 == steps {
            let p = &g.particles;
            for id in 0..p.len() {
                let k = g.slot(id);
                for x in [p.pos[k].x, p.pos[k].y, p.vel[k].x, p.vel[k].y] {
                    h.f(x);
                }
                h.f(p.omega[k]);
                h.f(p.theta[k]);
            }
            for w in &g.walls {
                h.f(w.force.x);
                h.f(w.force.y);
            }
        }
    }
    h.0
}

/// Hash of a coupled run: disc states by id and the disc–body contact
/// forces, every step.
fn coupled_hash(src: &str) -> u64 {
    let sc = scenario::parse(src, "t.toml").expect("valid scenario");
    let mut b = efgdem::coupling::run::build(&sc).expect("builds");
    let mut h = Hash::new();
    for _ in 0..b.steps {
        b.model.step().expect("steps");
        let g = &b.model.granular;
        let p = &g.particles;
        for id in 0..p.len() {
            let k = g.slot(id);
            for x in [p.pos[k].x, p.pos[k].y, p.vel[k].x, p.vel[k].y, p.omega[k]] {
                h.f(x);
            }
        }
        for c in &b.model.contacts {
            h.f(c.force.x);
            h.f(c.force.y);
            h.f(c.fs);
        }
    }
    h.0
}

/// Hashes of the same runs made with the code before issue 13 (commit
/// 31cfbc0, printed by this test then): a loose packing with dashpots,
/// the same with local damping only (no dashpot: both caps are `k_n δ`,
/// so the default needs no pin), the rigid nine-disc Test 1 and the EFG
/// nine-disc Test 1.
const GOLDEN: [(&str, u64); 4] = [
    ("packing, dashpots", 0xd72d4e5bb189b4c9),
    ("packing, local damping", 0x91e0b02f06fa44ed),
    ("nine discs rigid, test 1", 0xb9c022c14b04f4f1),
    ("nine discs EFG, test 1", 0x8d35402e83744cdc),
];

#[test]
fn rolling_friction_zero_is_bitwise_the_old_code() {
    // the pre-issue-13 code knew neither field: GOLDEN was made with PIN = ""
    const PIN: &str = "slip_normal = \"elastic\"\nrolling_friction = 0.0";
    let dashpots = "{ kind = \"critical-ratio\", zeta = 0.3, zeta_shear = 0.05 }";
    let local = "{ kind = \"local\", alpha = 0.3 }";
    let got = [
        dem_hash(&with_fields(&packing(dashpots), PIN)),
        dem_hash(&packing(local)),
        dem_hash(&with_fields(
            include_str!("../examples/nine_disc_rigid_test1.toml"),
            PIN,
        )),
        coupled_hash(&with_fields(
            include_str!("../examples/paper_nine_disc_test1.toml"),
            PIN,
        )),
    ];
    for ((name, want), got) in GOLDEN.iter().zip(got) {
        println!("(\"{name}\", {got:#018x}),");
        assert_eq!(got, *want, "{name}: not bitwise the old result");
    }
}
