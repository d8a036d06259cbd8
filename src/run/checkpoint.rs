//! `checkpoint.bin`: everything a run needs to continue as if it had never
//! stopped — the model's state ([`ModelState`]), the driver's own running
//! values (energy account, extrema, events), and the output cursors (length
//! of `history.csv`, the `.pvd` series' entries) — with a format version,
//! a fingerprint of the scenario and a CRC-32 of the whole content, written
//! atomically. A damaged file (any single flipped bit, a cut, an overwrite)
//! is refused with its path rather than used.

use super::RunError;
use crate::model::{Model, ModelState};
use crate::scenario::Scenario;
use crate::scenario::granular::{DiscsSpec, DiscsTable};
use serde::{Deserialize, Serialize, de::DeserializeOwned};
use std::io::Write;
use std::path::{Path, PathBuf};

/// First bytes of a checkpoint file.
const MAGIC: &[u8; 8] = b"EFGDEMCK";
/// Version of the envelope below (the model state has its own).
/// (3: a CRC-32 of the file's content at its end.)
const VERSION: u32 = 3;

/// File name of the checkpoint in the output directory.
pub const FILE: &str = "checkpoint.bin";

/// What a checkpoint holds.
#[derive(Serialize, Deserialize)]
pub(super) struct Checkpoint {
    /// [`fingerprint`] of the scenario that was run.
    pub scenario: u64,
    /// [`ModelState::to_bytes`].
    pub model: Vec<u8>,
    /// The driver's running values (postcard).
    pub driver: Vec<u8>,
    /// Length of `history.csv` at the checkpoint.
    pub history_bytes: u64,
    /// The `.pvd` series' entries `(time, file)`.
    pub series: Vec<Vec<(f64, String)>>,
    /// Where it was read from (for messages).
    #[serde(skip)]
    path: PathBuf,
}

/// A fingerprint of the scenario's content (FNV-1a 64 of its parsed form,
/// so comments and layout do not count, and of the bytes of the discs' CSV
/// file if it reads one): a restart refuses a checkpoint of another
/// scenario or of other discs.
pub(super) fn fingerprint(sc: &Scenario) -> u64 {
    let mut text = {
        let mut sc = sc.clone();
        sc.source = None;
        format!("{sc:?}").into_bytes()
    };
    if let Some(DiscsSpec::Table(DiscsTable { csv: Some(csv), .. })) =
        sc.granular.as_ref().map(|g| &g.discs)
    {
        // an unreadable file fails the build with its own error
        text.extend(
            crate::scenario::read_bounded(&sc.resolve(csv), crate::scenario::MAX_CSV_BYTES)
                .unwrap_or_default(),
        );
    }
    text.iter().fold(0xcbf2_9ce4_8422_2325u64, |h, &b| {
        (h ^ b as u64).wrapping_mul(0x0100_0000_01b3)
    })
}

impl Checkpoint {
    /// The checkpoint of `model` and the driver's values now.
    pub fn new(
        sc: &Scenario,
        model: &Model,
        driver: &impl Serialize,
        history_bytes: u64,
        series: Vec<Vec<(f64, String)>>,
    ) -> Self {
        Checkpoint {
            scenario: fingerprint(sc),
            model: model.save_state().to_bytes(),
            driver: postcard::to_stdvec(driver).expect("driver values serialise"),
            history_bytes,
            series,
            path: PathBuf::new(),
        }
    }

    /// Write to `path` atomically (temporary file, synced, renamed):
    /// [`MAGIC`], [`VERSION`], the content, its CRC-32.
    pub fn write(&self, path: &Path) -> std::io::Result<()> {
        let mut bytes = MAGIC.to_vec();
        bytes.extend_from_slice(&VERSION.to_le_bytes());
        postcard::to_io(self, &mut bytes).expect("a checkpoint serialises");
        bytes.extend_from_slice(&crc32fast::hash(&bytes).to_le_bytes());
        crate::output::write_atomic(path, true, |f| f.write_all(&bytes))
    }

    /// Read `path` and check it is whole and belongs to `sc`.
    pub fn read(path: &Path, sc: &Scenario) -> Result<Self, RunError> {
        let bad = |message: String| RunError::Restart {
            path: path.to_path_buf(),
            message,
        };
        let bytes = read_checkpoint_file(path).map_err(|e| bad(e.to_string()))?;
        let Some(body) = bytes.strip_prefix(MAGIC) else {
            return Err(bad("not an efgdem checkpoint".into()));
        };
        let (version, body) = body.split_at_checked(4).unwrap_or((&[], &[]));
        if version != VERSION.to_le_bytes() {
            return Err(bad(format!(
                "checkpoint format {version:?} is not this efgdem's ({VERSION})"
            )));
        }
        let Some((body, crc)) = body.split_last_chunk::<4>() else {
            return Err(bad("damaged checkpoint: cut short".into()));
        };
        if crc32fast::hash(&bytes[..bytes.len() - 4]) != u32::from_le_bytes(*crc) {
            return Err(bad(
                "damaged checkpoint: its content does not match its checksum (the file was altered or cut short after it was written); run the scenario afresh or use an intact copy".into(),
            ));
        }
        let mut ck: Checkpoint =
            postcard::from_bytes(body).map_err(|e| bad(format!("damaged checkpoint: {e}")))?;
        ck.path = path.to_path_buf();
        if ck.scenario != fingerprint(sc) {
            return Err(bad(
                "the scenario has changed since the checkpoint was written (only comments and layout may change, and not the discs' CSV file); run it afresh".into(),
            ));
        }
        Ok(ck)
    }

    /// Put the model in the checkpointed state (`model` freshly built from
    /// the same scenario).
    pub fn restore(&self, model: &mut Model) -> Result<(), RunError> {
        let bad = |message: String| RunError::Restart {
            path: self.path.clone(),
            message,
        };
        let state = ModelState::from_bytes(&self.model).map_err(|e| bad(e.to_string()))?;
        model.restore_state(&state).map_err(|e| bad(e.to_string()))
    }

    /// The driver's values.
    pub fn driver<D: DeserializeOwned>(&self) -> Result<D, RunError> {
        postcard::from_bytes(&self.driver).map_err(|e| RunError::Restart {
            path: self.path.clone(),
            message: format!("damaged driver values: {e}"),
        })
    }
}

/// The bytes of the checkpoint file `path`: its first bytes only unless
/// they are [`MAGIC`] (a device or another file is not read on).
fn read_checkpoint_file(path: &Path) -> std::io::Result<Vec<u8>> {
    use std::io::Read;
    let mut f = std::fs::File::open(path)?;
    let mut bytes = Vec::new();
    (&mut f).take(MAGIC.len() as u64).read_to_end(&mut bytes)?;
    if bytes == MAGIC {
        f.read_to_end(&mut bytes)?;
    }
    Ok(bytes)
}

/// Where a run's checkpoints go.
pub(super) fn path(out_dir: &Path) -> PathBuf {
    out_dir.join(FILE)
}
