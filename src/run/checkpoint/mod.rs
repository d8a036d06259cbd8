//! `checkpoint.bin`: everything a run needs to continue as if it had never
//! stopped — the model's state ([`ModelState`]), the driver's own running
//! values (energy account, extrema, events), and the output cursors (length
//! of `history.csv`, the `.pvd` series' entries) — with a format version,
//! a fingerprint of the scenario and a CRC-32 of the whole content, written
//! atomically. A damaged file (any single flipped bit, a cut, an overwrite)
//! is refused with its path rather than used.
//!
//! The discs' per-slot arrays and the pairs' arrays of a granular or
//! coupled state are stored raw after a small header (the `layout`
//! module), so that a run restarted on several ranks reads on each rank
//! only the discs and pairs of its region (`read_part`); one process
//! reads the file whole (`Checkpoint::read`). The layout:
//! `docs/reference/outputs.md`.

mod layout;
mod parts;

pub(super) use parts::read_part;

use super::RunError;
use crate::dem::state::GranularState;
use crate::model::{Model, ModelState, SystemState};
use crate::scenario::Scenario;
use crate::scenario::granular::{DiscsSpec, DiscsTable};
use layout::{Arrays, Table};
use serde::{Deserialize, Serialize, de::DeserializeOwned};
use std::fs::File;
use std::io::{BufReader, Read, Write};
use std::path::{Path, PathBuf};

/// First bytes of a checkpoint file.
const MAGIC: &[u8; 8] = b"EFGDEMCK";
/// Version of the file's layout (the model state has its own).
/// (3: a CRC-32 of the file's content at its end;
/// 4: the discs' and pairs' arrays raw after a header.)
const VERSION: u32 = 4;
/// Bytes before the header: [`MAGIC`], [`VERSION`] (u32) and the
/// header's length (u64), little endian.
const LEAD: u64 = 8 + 4 + 8;

/// File name of the checkpoint in the output directory.
pub const FILE: &str = "checkpoint.bin";

/// The header of a checkpoint file (postcard): all but the raw arrays.
#[derive(Serialize, Deserialize)]
struct Head {
    /// [`fingerprint`] of the scenario that was run.
    scenario: u64,
    /// [`ModelState::to_bytes`] of the state without its raw arrays.
    model: Vec<u8>,
    /// The raw arrays that follow the header (none for a continuum).
    table: Option<Table>,
    /// The driver's running values (postcard).
    driver: Vec<u8>,
    /// Length of `history.csv` at the checkpoint.
    history_bytes: u64,
    /// The `.pvd` series' entries `(time, file)`.
    series: Vec<Vec<(f64, String)>>,
}

/// What a checkpoint holds.
pub(super) struct Checkpoint {
    /// [`fingerprint`] of the scenario that was run.
    scenario: u64,
    /// The model's state: to write, or read whole until it is restored
    /// (`None` after, and for a rank that read its part).
    state: Option<ModelState>,
    /// The driver's running values (postcard).
    driver: Vec<u8>,
    /// Length of `history.csv` at the checkpoint.
    pub history_bytes: u64,
    /// The `.pvd` series' entries `(time, file)`.
    pub series: Vec<Vec<(f64, String)>>,
    /// Where it was read from (for messages).
    path: PathBuf,
}

/// The granular state in `s`, if it has one (a granular or coupled model).
fn granular_of(s: &mut ModelState) -> Option<&mut GranularState> {
    match &mut s.system {
        SystemState::Granular(g) => Some(g),
        SystemState::Coupled(c) => Some(&mut c.granular),
        SystemState::Continuum(_) => None,
    }
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
            state: Some(model.save_state()),
            driver: postcard::to_stdvec(driver).expect("driver values serialise"),
            history_bytes,
            series,
            path: PathBuf::new(),
        }
    }

    /// Write to `path` atomically (temporary file, synced, renamed):
    /// [`MAGIC`], [`VERSION`], the header's length and the header, the
    /// raw arrays, the CRC-32 of all that.
    pub fn write(mut self, path: &Path) -> std::io::Result<()> {
        let mut state = self
            .state
            .take()
            .expect("a checkpoint to write has a state");
        let arrays = granular_of(&mut state).map(layout::take);
        let head = Head {
            scenario: self.scenario,
            model: state.to_bytes(),
            table: arrays.as_ref().map(Table::of),
            driver: std::mem::take(&mut self.driver),
            history_bytes: self.history_bytes,
            series: std::mem::take(&mut self.series),
        };
        let head = postcard::to_stdvec(&head).expect("a checkpoint's header serialises");
        crate::output::write_atomic(path, true, |f| {
            let mut w = Hashing {
                inner: f,
                crc: crc32fast::Hasher::new(),
            };
            w.write_all(MAGIC)?;
            w.write_all(&VERSION.to_le_bytes())?;
            w.write_all(&(head.len() as u64).to_le_bytes())?;
            w.write_all(&head)?;
            if let Some(a) = &arrays {
                layout::write(a, &mut w)?;
            }
            let crc = w.crc.finalize();
            f.write_all(&crc.to_le_bytes())
        })
    }

    /// Read `path` whole and check it is whole and belongs to `sc`.
    pub fn read(path: &Path, sc: &Scenario) -> Result<Self, RunError> {
        let bad = |message: String| RunError::Restart {
            path: path.to_path_buf(),
            message,
        };
        let mut o = Opened::open(path, sc, true).map_err(bad)?;
        let mut state = std::mem::replace(&mut o.state, empty_state());
        if let (Some(g), Some(a)) = (granular_of(&mut state), o.arrays.as_mut()) {
            let arrays = a
                .read_all()
                .map_err(|e| bad(format!("damaged checkpoint: {e}")))?;
            layout::put_back(g, arrays);
        }
        Ok(o.into_checkpoint(Some(state)))
    }

    /// Put the model in the checkpointed state (`model` freshly built from
    /// the same scenario); the checkpoint lets go of it.
    pub fn restore(&mut self, model: &mut Model) -> Result<(), RunError> {
        let bad = |message: String| RunError::Restart {
            path: self.path.clone(),
            message,
        };
        let state = self
            .state
            .take()
            .ok_or_else(|| bad("the checkpoint's state was restored already".into()))?;
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

/// A state without anything in it (a placeholder).
fn empty_state() -> ModelState {
    ModelState {
        step: 0,
        system: SystemState::Continuum(Vec::new()),
    }
}

/// A writer that hashes what it writes.
struct Hashing<'a, W: Write> {
    inner: &'a mut W,
    crc: crc32fast::Hasher,
}

impl<W: Write> Write for Hashing<'_, W> {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        let n = self.inner.write(buf)?;
        self.crc.update(&buf[..n]);
        Ok(n)
    }

    fn flush(&mut self) -> std::io::Result<()> {
        self.inner.flush()
    }
}

/// A checkpoint file opened: its header checked and decoded, its raw
/// arrays ready to be read.
struct Opened {
    head: Head,
    /// The model's state without its raw arrays.
    state: ModelState,
    arrays: Option<Arrays<File>>,
    path: PathBuf,
}

impl Opened {
    /// Open `path`: a checkpoint of this format (else refused), its
    /// content matching its CRC-32 if `crc` (the whole file is read for
    /// it), of a size that fits its header, of the scenario `sc`. The
    /// refusal's message.
    fn open(path: &Path, sc: &Scenario, crc: bool) -> Result<Opened, String> {
        let f = File::open(path).map_err(|e| e.to_string())?;
        let len = f.metadata().map_err(|e| e.to_string())?.len();
        let mut r = BufReader::with_capacity(1 << 20, f);
        let head_len = lead(&mut r)?;
        if crc {
            check_crc(path, len)?;
        }
        let short = || "damaged checkpoint: cut short".to_string();
        let head_len = head_len
            .filter(|&h| h <= len.saturating_sub(LEAD + 4))
            .ok_or_else(short)?;
        let (head, state) = read_head(&mut r, head_len, sc)?;
        let arrays = head.table.map_or(Some(0), |t| t.bytes());
        if arrays.and_then(|a| a.checked_add(LEAD + head_len + 4)) != Some(len) {
            return Err(
                "damaged checkpoint: its size does not match its header (cut short or extended)"
                    .into(),
            );
        }
        let base = LEAD + head_len;
        let arrays = head.table.map(|t| Arrays::new(r, base, base, t));
        Ok(Opened {
            head,
            state,
            arrays,
            path: path.to_path_buf(),
        })
    }

    /// The checkpoint with its header's values and `state`.
    fn into_checkpoint(self, state: Option<ModelState>) -> Checkpoint {
        Checkpoint {
            scenario: self.head.scenario,
            state,
            driver: self.head.driver,
            history_bytes: self.head.history_bytes,
            series: self.head.series,
            path: self.path,
        }
    }
}

/// The first bytes of a checkpoint: [`MAGIC`] and [`VERSION`] (else
/// refused), then the header's length (`None` if the file ends before).
fn lead(r: &mut impl Read) -> Result<Option<u64>, String> {
    let mut lead = [0u8; LEAD as usize];
    // a device or another file: its first bytes only
    let got = read_up_to(r, &mut lead).map_err(|e| e.to_string())?;
    if got < 8 || lead[..8] != MAGIC[..] {
        return Err("not an efgdem checkpoint".into());
    }
    if got < 12 || lead[8..12] != VERSION.to_le_bytes() {
        let v = match got {
            12.. => u32::from_le_bytes(lead[8..12].try_into().expect("4 bytes")).to_string(),
            _ => "?".into(),
        };
        return Err(format!(
            "checkpoint format {v} is not this efgdem's ({VERSION}), or the file is damaged; run the scenario afresh"
        ));
    }
    Ok((got == lead.len()).then(|| u64::from_le_bytes(lead[12..].try_into().expect("8 bytes"))))
}

/// The header of `head_len` bytes (no more than the file holds) and the
/// model's state in it, of the scenario `sc` (else refused).
fn read_head(
    r: &mut impl Read,
    head_len: u64,
    sc: &Scenario,
) -> Result<(Head, ModelState), String> {
    let damaged = |e: &dyn std::fmt::Display| format!("damaged checkpoint: {e}");
    let mut head = vec![0u8; head_len as usize];
    r.read_exact(&mut head).map_err(|e| damaged(&e))?;
    let head: Head = postcard::from_bytes(&head).map_err(|e| damaged(&e))?;
    if head.scenario != fingerprint(sc) {
        return Err(
            "the scenario has changed since the checkpoint was written (only comments and layout may change, and not the discs' CSV file); run it afresh".into(),
        );
    }
    let mut state = ModelState::from_bytes(&head.model).map_err(|e| damaged(&e))?;
    if granular_of(&mut state).is_some() != head.table.is_some() {
        return Err("damaged checkpoint: its arrays do not match its model".into());
    }
    Ok((head, state))
}

/// Read into `buf` until it is full or the file ends: the bytes read.
fn read_up_to(r: &mut impl Read, buf: &mut [u8]) -> std::io::Result<usize> {
    let mut got = 0;
    while got < buf.len() {
        match r.read(&mut buf[got..])? {
            0 => break,
            n => got += n,
        }
    }
    Ok(got)
}

/// Whether the `len` bytes of the file at `path` end with the CRC-32 of
/// the others (read a block at a time); the refusal's message if not.
fn check_crc(path: &Path, len: u64) -> Result<(), String> {
    let short = || "damaged checkpoint: cut short".to_string();
    let body = len.checked_sub(4).ok_or_else(short)?;
    let mut f = File::open(path).map_err(|e| e.to_string())?;
    let mut crc = crc32fast::Hasher::new();
    let mut buf = vec![0u8; 1 << 20];
    let mut left = body;
    while left > 0 {
        let k = left.min(buf.len() as u64) as usize;
        f.read_exact(&mut buf[..k]).map_err(|_| short())?;
        crc.update(&buf[..k]);
        left -= k as u64;
    }
    let mut end = [0u8; 4];
    f.read_exact(&mut end).map_err(|_| short())?;
    if crc.finalize() != u32::from_le_bytes(end) {
        return Err(
            "damaged checkpoint: its content does not match its checksum (the file was altered or cut short after it was written); run the scenario afresh or use an intact copy".into(),
        );
    }
    Ok(())
}

/// Where a run's checkpoints go.
pub(super) fn path(out_dir: &Path) -> PathBuf {
    out_dir.join(FILE)
}
