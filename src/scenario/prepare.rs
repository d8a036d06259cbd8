//! The preparation of a generated packing (`method = "deposit"` or
//! `"grow"`): stepped under a watch (progress, a stop request), or read
//! back from its `cache` file.
//!
//! The cache is a disc CSV file (`x,y,r,id`, also a valid `csv` disc
//! source) whose `#` header lines record what determined the packing — the
//! generator's fields, the preparation's contact law, the discs' density
//! and thickness, gravity, the efgdem version — and a checksum of its
//! rows. A run reads it when that record is the scenario's and the rows
//! are intact, and refuses it, saying what differs, otherwise; a missing
//! file is prepared and written (atomically). The read packing is the
//! prepared one bit for bit (shortest round-trip decimals): a run from the
//! cache gives the same results as one that prepares.

use super::build::{bad, loose_rows, preparation, settle_law, spec};
use super::granular::{DiscsSpec, DiscsTable, Packing};
use super::{Invalid, Scenario};
use crate::dem::DemError;
use crate::dem::packing::{DiscRow, Watch, grow_in_box, settle_in_box};
use crate::geom::Vec2;
use crate::scenario::generate::discs_from_csv;
use std::path::{Path, PathBuf};

/// A prepared packing.
#[derive(Debug, Clone)]
pub struct Bed {
    /// The discs, in scenario order.
    pub rows: Vec<DiscRow>,
    /// The cache file it was read from (`None`: prepared now).
    pub read_from: Option<PathBuf>,
    /// The cache file it was written to.
    pub written_to: Option<PathBuf>,
    /// Why the cache file could not be written (the bed is still good:
    /// the run goes on with it).
    pub cache_error: Option<String>,
}

/// Why a preparation did not give a packing.
#[derive(Debug)]
pub enum PrepareError {
    /// Bad input, a cache that does not match, or a failed preparation.
    Invalid(Invalid),
    /// The watch stopped it after `step` of `steps` steps.
    Stopped {
        /// Steps done.
        step: usize,
        /// Steps of the whole preparation.
        steps: usize,
    },
}

impl From<Invalid> for PrepareError {
    fn from(e: Invalid) -> Self {
        PrepareError::Invalid(e)
    }
}

fn table(sc: &Scenario) -> Result<&DiscsTable, Invalid> {
    match &spec(sc)?.discs {
        DiscsSpec::Table(t) => Ok(t),
        DiscsSpec::Inline(_) => Err(bad("granular.discs", "not a generated packing")),
    }
}

/// The scenario's prepared packing, `None` if it has no preparation:
/// read from its `cache` when that holds it, else prepared (`watch` sees
/// every step and may stop it) and written to the `cache`. Bodies in the
/// region the preparation will fill are refused first
/// ([`super::fill::check_bodies`]).
pub fn prepare(sc: &Scenario, watch: Watch) -> Result<Option<Bed>, PrepareError> {
    let Some(prep) = preparation(sc) else {
        return Ok(None);
    };
    // a run that would not fit is refused before anything is generated
    super::build::check_memory(sc)?;
    let t = table(sc)?;
    let cache = t.cache.as_ref().map(|c| sc.resolve(c));
    if let Some(rows) = read_cache(sc, cache.as_deref())? {
        return Ok(Some(Bed {
            rows,
            read_from: cache,
            written_to: None,
            cache_error: None,
        }));
    }
    let loose = loose_rows(sc, t)?;
    super::fill::check_bodies(sc, &loose)?;
    let thickness = spec(sc)?.thickness;
    let (law, density) = settle_law(sc, t)?;
    let (lo, hi) = t.region.map_or((Vec2::ZERO, Vec2::ZERO), |[a, b]| {
        (Vec2::from(a), Vec2::from(b))
    });
    let result = match prep.method {
        Packing::Grow => {
            let radius = t.radius.map_or((0.0, 0.0), |r| r.range());
            let (n, steps) = (loose.len(), prep.steps);
            grow_in_box(
                lo, hi, radius, n, t.seed, steps, law, density, thickness, watch,
            )
        }
        _ => {
            let g = deposit_gravity(sc);
            settle_in_box(
                &loose, lo, hi, law, density, thickness, g, prep.steps, watch,
            )
        }
    };
    let rows = result.map_err(|e| match e {
        DemError::Stopped { step } => PrepareError::Stopped {
            step,
            steps: prep.steps,
        },
        e => PrepareError::Invalid(bad("granular.discs", e)),
    })?;
    // a cache that cannot be written loses nothing but the cache
    let (written_to, cache_error) = match cache {
        Some(path) => match write_cache(sc, &path, &rows) {
            Ok(()) => (Some(path), None),
            Err(e) => (None, Some(format!("{}: {e}", path.display()))),
        },
        None => (None, None),
    };
    Ok(Some(Bed {
        rows,
        read_from: None,
        written_to,
        cache_error,
    }))
}

/// The packing in the scenario's `cache` file, if it has one that holds
/// it (no stepping: what `check` uses); an error if the file is there but
/// holds another packing.
pub fn cached(sc: &Scenario) -> Result<Option<Vec<DiscRow>>, Invalid> {
    if preparation(sc).is_none() {
        return Ok(None);
    }
    let cache = table(sc)?.cache.as_ref().map(|c| sc.resolve(c));
    read_cache(sc, cache.as_deref())
}

/// The gravity of a deposit: the scenario's, or −9.81 ŷ if it has none.
pub fn deposit_gravity(sc: &Scenario) -> Vec2 {
    let g = Vec2::from(sc.simulation.gravity);
    if g.norm2() > 0.0 {
        g
    } else {
        Vec2::new(0.0, -9.81)
    }
}

/// What determines the packing, as `(key, value)` lines of the cache's
/// header (values in shortest round-trip form).
fn record(sc: &Scenario) -> Result<Vec<(&'static str, String)>, Invalid> {
    let t = table(sc)?;
    let (law, density) = settle_law(sc, t)?;
    let method = t.method;
    Ok(vec![
        ("efgdem", env!("CARGO_PKG_VERSION").to_string()),
        ("method", format!("{method:?}").to_lowercase()),
        ("box", format!("{:?}", t.region)),
        ("radius", format!("{:?}", t.radius.map(|r| r.range()))),
        ("count", format!("{:?}", t.count)),
        ("seed", t.seed.to_string()),
        ("jitter", format!("{:?}", t.jitter)),
        (
            "settle_steps",
            format!("{:?}", preparation(sc).map(|p| p.steps)),
        ),
        ("contact law", format!("{law:?}")),
        ("density", format!("{density:?}")),
        ("thickness", format!("{:?}", spec(sc)?.thickness)),
        (
            "gravity",
            match method {
                Packing::Grow => "none".to_string(),
                _ => format!("{:?}", deposit_gravity(sc).to_array()),
            },
        ),
    ])
}

/// FNV-1a (64 bits) of `bytes`.
fn fnv1a(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325u64, |h, &b| {
        (h ^ b as u64).wrapping_mul(0x0100_0000_01b3)
    })
}

/// The rows of a cache file as text (what its checksum covers).
fn rows_text(rows: &[DiscRow]) -> String {
    let mut s = String::from("x,y,r,id\n");
    for (k, r) in rows.iter().enumerate() {
        s.push_str(&format!(
            "{:e},{:e},{:e},{}\n",
            r.pos.x,
            r.pos.y,
            r.r,
            k + 1
        ));
    }
    s
}

const HEADER: &str = "# efgdem prepared packing";

fn write_cache(sc: &Scenario, path: &Path, rows: &[DiscRow]) -> std::io::Result<()> {
    let body = rows_text(rows);
    let mut s =
        format!("{HEADER} (reused by runs of the same packing; delete it to prepare again)\n");
    for (k, v) in record(sc).map_err(|e| std::io::Error::other(e.message))? {
        s.push_str(&format!("# {k}: {v}\n"));
    }
    s.push_str(&format!("# checksum: {:016x}\n", fnv1a(body.as_bytes())));
    s.push_str(&body);
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir)?;
    }
    let tmp = path.with_extension("tmp");
    std::fs::write(&tmp, s)?;
    std::fs::rename(&tmp, path)
}

/// The rows of the cache at `path` if it exists (`None` otherwise), checked
/// against the scenario's record and its checksum.
fn read_cache(sc: &Scenario, path: Option<&Path>) -> Result<Option<Vec<DiscRow>>, Invalid> {
    let Some(path) = path.filter(|p| p.exists()) else {
        return Ok(None);
    };
    let at = "granular.discs.cache";
    let refuse = |why: String| {
        bad(
            at,
            format!(
                "{}: {why}; delete the file to prepare the packing again (and save it there), or name another `cache`",
                path.display()
            ),
        )
    };
    let text = super::read_text(path, super::MAX_CSV_BYTES)
        .map_err(|e| refuse(format!("cannot read it ({e})")))?;
    if !text.starts_with(HEADER) {
        return Err(refuse("not a packing efgdem prepared".into()));
    }
    let header: Vec<(&str, &str)> = text
        .lines()
        .filter_map(|l| l.strip_prefix("# ")?.split_once(": "))
        .collect();
    let differ: Vec<String> = record(sc)?
        .into_iter()
        .filter_map(|(k, v)| {
            let old = header.iter().find(|h| h.0 == k).map_or("(none)", |h| h.1);
            (old != v).then(|| format!("{k} {old} in the file, {v} now"))
        })
        .collect();
    if !differ.is_empty() {
        return Err(refuse(format!(
            "it holds a packing prepared with other settings ({})",
            differ.join("; ")
        )));
    }
    let rows = discs_from_csv(&text).map_err(|e| refuse(format!("unreadable: {e}")))?;
    let sum = header.iter().find(|h| h.0 == "checksum").map(|h| h.1);
    if sum != Some(&format!("{:016x}", fnv1a(rows_text(&rows).as_bytes()))) {
        return Err(refuse(
            "its rows have been changed since it was written".into(),
        ));
    }
    Ok(Some(rows))
}
