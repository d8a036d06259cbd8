//! VTK XML files, written by hand (see docs/reference/rust-api.md, "What is written by
//! hand"): the `.pvd` time series, and [`VtkFile`], which writes the
//! arrays of a `.vtu`/`.vtp` in one of the [`VtkFormat`]s — by default
//! binary, appended raw after the XML, each array zlib-compressed in 32 KiB
//! blocks (VTK file version 1.0, `header_type="UInt64"`,
//! `compressor="vtkZLibDataCompressor"`), as ParaView writes them itself.

pub use crate::scenario::VtkFormat;
use flate2::{Compress, Compression, FlushCompress, Status};
use rayon::prelude::*;
use std::fmt::Write as _;
use std::fs::File;
use std::io::{Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};

/// Start of a `.pvd` file, before its entries.
const PVD_HEAD: &str = "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"LittleEndian\">\n<Collection>\n";
/// End of a `.pvd` file, after its entries.
const PVD_TAIL: &str = "</Collection>\n</VTKFile>\n";

/// A `.pvd` collection that is a complete, readable file after every frame
/// without being rewritten: the first frame writes the whole file
/// (temporary file + rename); every later one writes its entry over the
/// closing tail, followed by the tail again, in one `write` at that offset.
/// The file only grows, and the bytes are those of a file written whole.
pub struct PvdSeries {
    path: PathBuf,
    entries: Vec<(f64, String)>,
    /// The open file and the offset of its closing tail, once written.
    file: Option<(File, u64)>,
}

impl PvdSeries {
    /// An empty collection to be written at `path` (nothing is written
    /// before the first frame).
    pub fn new(path: &Path) -> Self {
        PvdSeries {
            path: path.to_path_buf(),
            entries: Vec::new(),
            file: None,
        }
    }

    /// The `.pvd` line of frame `file` at time `t`.
    fn entry(t: f64, file: &str) -> String {
        format!("<DataSet timestep=\"{t:e}\" part=\"0\" file=\"{file}\"/>\n")
    }

    /// Register a frame file (path relative to the `.pvd`) at time `t`.
    pub fn add(&mut self, t: f64, file: &str) -> std::io::Result<()> {
        self.entries.push((t, file.to_string()));
        match &mut self.file {
            None => self.write_whole(),
            Some((f, tail)) => {
                let line = Self::entry(t, file);
                let mut buf = String::with_capacity(line.len() + PVD_TAIL.len());
                buf.push_str(&line);
                buf.push_str(PVD_TAIL);
                let at = *tail;
                let written = f
                    .seek(SeekFrom::Start(at))
                    .and_then(|_| f.write_all(buf.as_bytes()));
                if let Err(e) = written {
                    // put the closing tail back where it was (no more room
                    // is needed), so the file stays whole without the entry
                    self.entries.pop();
                    let _ = f
                        .seek(SeekFrom::Start(at))
                        .and_then(|_| f.write_all(PVD_TAIL.as_bytes()))
                        .and_then(|_| f.set_len(at + PVD_TAIL.len() as u64));
                    return Err(super::io_at(&self.path, e));
                }
                *tail += line.len() as u64;
                Ok(())
            }
        }
    }

    /// The frames registered so far: `(time, file)`.
    pub fn entries(&self) -> &[(f64, String)] {
        &self.entries
    }

    /// Replace the entries (a restart continues the series it checkpointed)
    /// and write the file whole with them — the same bytes as the series
    /// had when it held these entries. No entries: no file (one left by
    /// the stopped run is removed), as before the first frame.
    pub fn resume(&mut self, entries: Vec<(f64, String)>) -> std::io::Result<()> {
        self.entries = entries;
        self.file = None;
        if !self.entries.is_empty() {
            return self.write_whole();
        }
        match std::fs::remove_file(&self.path) {
            Err(e) if e.kind() != std::io::ErrorKind::NotFound => Err(e),
            _ => Ok(()),
        }
    }

    /// Write the collection whole (temporary file + rename) and keep it
    /// open for the next entries.
    fn write_whole(&mut self) -> std::io::Result<()> {
        let mut s = String::from(PVD_HEAD);
        for (t, f) in &self.entries {
            s.push_str(&Self::entry(*t, f));
        }
        let tail = s.len() as u64;
        s.push_str(PVD_TAIL);
        super::write_atomic(&self.path, false, |f| f.write_all(s.as_bytes()))?;
        let f = File::options()
            .write(true)
            .open(&self.path)
            .map_err(|e| super::io_at(&self.path, e))?;
        self.file = Some((f, tail));
        Ok(())
    }
}

/// A value type of a data array.
pub trait Scalar: Copy + Send + Sync {
    /// VTK's name of the type (`Float64`, `Int64`, …).
    const TYPE: &'static str;
    /// Append the little-endian bytes.
    fn put_le(self, out: &mut Vec<u8>);
    /// Append the text form (exact: `f64` round-trips).
    fn put_ascii(self, out: &mut String);
}

macro_rules! scalar {
    ($t:ty, $name:literal, $fmt:literal) => {
        impl Scalar for $t {
            const TYPE: &'static str = $name;
            #[inline]
            fn put_le(self, out: &mut Vec<u8>) {
                out.extend_from_slice(&self.to_le_bytes());
            }
            #[inline]
            fn put_ascii(self, out: &mut String) {
                let _ = write!(out, $fmt, self);
            }
        }
    };
}
scalar!(f64, "Float64", "{:e}");
scalar!(i64, "Int64", "{}");
scalar!(i32, "Int32", "{}");
scalar!(u8, "UInt8", "{}");

/// Uncompressed bytes per compressed block (VTK's default block size).
const BLOCK: usize = 1 << 15;
/// zlib level of the compressed blocks: 1, the fastest. On disc frames
/// (doubles that differ in their last bits) higher levels gain a few
/// percent in size at several times the time (docs/performance.md, "ParaView files").
const LEVEL: u32 = 1;

/// One VTK XML file being put together: the XML in `xml`, the binary
/// arrays in `appended` (offsets counted from the first byte after the
/// `_` that opens the appended data).
pub struct VtkFile {
    format: VtkFormat,
    xml: String,
    appended: Vec<u8>,
    /// Scratch: the raw bytes of the array being written.
    raw: Vec<u8>,
}

impl VtkFile {
    /// A file of dataset type `kind` (`"PolyData"`, `"UnstructuredGrid"`)
    /// with its arrays stored as `format`; the `<VTKFile>` and `<kind>`
    /// elements are opened.
    pub fn new(kind: &str, format: VtkFormat) -> Self {
        let mut xml = String::from("<?xml version=\"1.0\"?>\n");
        let _ = write!(
            xml,
            "<VTKFile type=\"{kind}\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\""
        );
        if format == VtkFormat::Binary {
            xml.push_str(" compressor=\"vtkZLibDataCompressor\"");
        }
        let _ = writeln!(xml, ">\n<{kind}>");
        VtkFile {
            format,
            xml,
            appended: Vec::new(),
            raw: Vec::new(),
        }
    }

    /// Open element `tag` with attributes `attrs` (`name="value" …`).
    pub fn open(&mut self, tag: &str, attrs: &str) {
        match attrs.is_empty() {
            true => {
                let _ = writeln!(self.xml, "<{tag}>");
            }
            false => {
                let _ = writeln!(self.xml, "<{tag} {attrs}>");
            }
        }
    }

    /// Close element `tag`.
    pub fn close(&mut self, tag: &str) {
        let _ = writeln!(self.xml, "</{tag}>");
    }

    /// A `<DataArray>` of `ncomp` components per tuple; `extra` are more
    /// attributes (`IdType="1"`, `ComponentName0="XX"`, …; may be empty).
    pub fn array<T: Scalar>(&mut self, name: &str, ncomp: usize, extra: &str, values: &[T]) {
        debug_assert!(ncomp > 0 && values.len().is_multiple_of(ncomp));
        let _ = write!(
            self.xml,
            "<DataArray type=\"{}\" Name=\"{name}\" NumberOfComponents=\"{ncomp}\"",
            T::TYPE
        );
        if !extra.is_empty() {
            self.xml.push(' ');
            self.xml.push_str(extra);
        }
        if self.format == VtkFormat::Ascii {
            self.xml.push_str(" format=\"ascii\">\n");
            for (i, &v) in values.iter().enumerate() {
                if i > 0 {
                    self.xml.push(if i % ncomp == 0 { '\n' } else { ' ' });
                }
                v.put_ascii(&mut self.xml);
            }
            self.xml.push_str("\n</DataArray>\n");
            return;
        }
        let _ = writeln!(
            self.xml,
            " format=\"appended\" offset=\"{}\"/>",
            self.appended.len()
        );
        self.raw.clear();
        self.raw.reserve(std::mem::size_of_val(values));
        for &v in values {
            v.put_le(&mut self.raw);
        }
        match self.format {
            VtkFormat::Binary => compress_into(&self.raw, &mut self.appended),
            _ => {
                self.appended
                    .extend_from_slice(&(self.raw.len() as u64).to_le_bytes());
                self.appended.extend_from_slice(&self.raw);
            }
        }
    }

    /// Close the dataset and write the file at `path` atomically
    /// (temporary file + rename: a reader never sees half a frame).
    pub fn write(mut self, kind: &str, path: &Path) -> std::io::Result<()> {
        self.close(kind);
        super::write_atomic(path, false, |w| {
            w.write_all(self.xml.as_bytes())?;
            if self.format != VtkFormat::Ascii {
                w.write_all(b"<AppendedData encoding=\"raw\">\n_")?;
                w.write_all(&self.appended)?;
                w.write_all(b"\n</AppendedData>\n")?;
            }
            w.write_all(b"</VTKFile>\n")
        })
    }
}

/// Arrays smaller than this are stored, not compressed: a few hundred
/// bytes saved do not pay for setting up a zlib stream (it clears a 128 kB
/// hash table; at a frame every step of Example 1 that was half the time).
const SMALL: usize = 4096;

/// Append `raw` as VTK compressed data: the header `[blocks, block size,
/// size of the last block if partial (else 0), compressed size of each
/// block]` (UInt64), then one zlib stream per block, compressed in
/// parallel. Small arrays, and the blocks of an array whose first block
/// shrinks by less than 10 % (doubles of physical values, e.g. radii or
/// spins), are stored (zlib streams of uncompressed deflate blocks), which
/// saves most of the time for a percent or two of size. The choice depends
/// on the data only, so the bytes do not depend on the number of threads.
fn compress_into(raw: &[u8], out: &mut Vec<u8>) {
    let mut blocks: Vec<Vec<u8>> = Vec::with_capacity(raw.len().div_ceil(BLOCK));
    if raw.len() < SMALL {
        if !raw.is_empty() {
            blocks.push(zlib_stored(raw));
        }
    } else {
        let first = &raw[..BLOCK.min(raw.len())];
        blocks.push(zlib(first));
        let rest = raw[first.len()..].par_chunks(BLOCK);
        match blocks[0].len() * 10 > first.len() * 9 {
            true => blocks.par_extend(rest.map(zlib_stored)),
            false => blocks.par_extend(rest.map(zlib)),
        }
    }
    let head = [blocks.len(), BLOCK, raw.len() % BLOCK];
    for v in head.into_iter().chain(blocks.iter().map(Vec::len)) {
        out.extend_from_slice(&(v as u64).to_le_bytes());
    }
    for b in &blocks {
        out.extend_from_slice(b);
    }
}

thread_local! {
    /// Per thread, a zlib stream of [`LEVEL`], reset and reused.
    static STREAM: std::cell::RefCell<Compress> =
        std::cell::RefCell::new(Compress::new(Compression::new(LEVEL), true));
}

/// `data` as one zlib stream of [`LEVEL`].
fn zlib(data: &[u8]) -> Vec<u8> {
    STREAM.with_borrow_mut(|z| {
        z.reset();
        // zlib's bound (stored blocks), which no level exceeds
        let mut out = Vec::with_capacity(data.len() + 5 * (data.len() / 16_000 + 1) + 64);
        loop {
            let read = z.total_in() as usize;
            match z.compress_vec(&data[read..], &mut out, FlushCompress::Finish) {
                Ok(Status::StreamEnd) => return out,
                Ok(_) => out.reserve(out.capacity().max(64)),
                Err(e) => unreachable!("zlib on memory: {e}"),
            }
        }
    })
}

/// `data` as a zlib stream (RFC 1950) of stored deflate blocks (RFC 1951
/// §3.2.4): header, blocks of at most 65 535 bytes, Adler-32.
fn zlib_stored(data: &[u8]) -> Vec<u8> {
    let mut out = Vec::with_capacity(data.len() + 5 * (data.len() / 65_535 + 1) + 6);
    out.extend_from_slice(&[0x78, 0x01]); // deflate, 32 kB window; (0x7801 % 31 == 0)
    let mut chunks = data.chunks(65_535).peekable();
    if data.is_empty() {
        out.extend_from_slice(&[1, 0, 0, 0xff, 0xff]);
    }
    while let Some(c) = chunks.next() {
        out.push(u8::from(chunks.peek().is_none())); // BFINAL, BTYPE = 00
        let n = c.len() as u16;
        out.extend_from_slice(&n.to_le_bytes());
        out.extend_from_slice(&(!n).to_le_bytes());
        out.extend_from_slice(c);
    }
    let (mut a, mut b) = (1u32, 0u32);
    for c in data.chunks(5552) {
        for &x in c {
            a += u32::from(x);
            b += a;
        }
        a %= 65_521;
        b %= 65_521;
    }
    out.extend_from_slice(&((b << 16) | a).to_be_bytes());
    out
}

/// 2-D vectors as 3-component tuples (z = 0), as VTK filters expect.
pub fn vec3(v: impl IntoIterator<Item = crate::geom::Vec2>) -> Vec<f64> {
    v.into_iter().flat_map(|p| [p.x, p.y, 0.0]).collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::Read;

    fn tmp(tag: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("efgdem-vtk-{tag}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    #[test]
    fn pvd_appended_equals_pvd_written_whole() {
        let d = tmp("pvd");
        let mut a = PvdSeries::new(&d.join("a.pvd"));
        for k in 0..5 {
            a.add(k as f64 * 0.1, &format!("frames/a_{k:07}.vtp"))
                .unwrap();
        }
        let mut b = PvdSeries::new(&d.join("b.pvd"));
        b.resume(a.entries().to_vec()).unwrap();
        let (ta, tb) = (
            std::fs::read_to_string(d.join("a.pvd")).unwrap(),
            std::fs::read_to_string(d.join("b.pvd")).unwrap(),
        );
        assert_eq!(ta, tb);
        assert!(ta.ends_with(PVD_TAIL) && ta.matches("<DataSet").count() == 5);
        // a restart from the first three entries continues to the same file
        let mut c = PvdSeries::new(&d.join("a.pvd"));
        c.resume(a.entries()[..3].to_vec()).unwrap();
        for (t, f) in &a.entries()[3..] {
            c.add(*t, f).unwrap();
        }
        assert_eq!(std::fs::read_to_string(d.join("a.pvd")).unwrap(), tb);
        std::fs::remove_dir_all(d).unwrap();
    }

    #[test]
    fn stored_zlib_streams_decompress() {
        for n in [0usize, 1, 5552, 65_535, 65_536, 200_000] {
            let data: Vec<u8> = (0..n).map(|i| (i * 7 + i / 300) as u8).collect();
            let mut back = Vec::new();
            flate2::read::ZlibDecoder::new(&zlib_stored(&data)[..])
                .read_to_end(&mut back)
                .unwrap();
            assert_eq!(back, data, "{n}");
        }
    }

    /// The compressed blocks decompress to the array, with VTK's header.
    #[test]
    fn compressed_arrays_have_vtk_block_headers() {
        let vals: Vec<f64> = (0..10_000).map(|i| (i as f64).sin()).collect();
        let mut f = VtkFile::new("PolyData", VtkFormat::Binary);
        f.array("a", 1, "", &[1i32, 2, 3]);
        f.array("b", 2, "", &vals);
        f.array("empty", 3, "", &[] as &[f64]);
        assert!(
            f.xml
                .contains("Name=\"b\" NumberOfComponents=\"2\" format=\"appended\"")
        );
        let off: usize = f
            .xml
            .split("Name=\"b\"")
            .nth(1)
            .unwrap()
            .split("offset=\"")
            .nth(1)
            .unwrap()
            .split('"')
            .next()
            .unwrap()
            .parse()
            .unwrap();
        let word = |k: usize| {
            u64::from_le_bytes(f.appended[off + 8 * k..off + 8 * k + 8].try_into().unwrap())
                as usize
        };
        let n = word(0);
        assert_eq!((n, word(1), word(2)), (3, BLOCK, 80_000 % BLOCK));
        let mut at = off + 8 * (3 + n);
        let mut raw = Vec::new();
        for k in 0..n {
            let len = word(3 + k);
            flate2::read::ZlibDecoder::new(&f.appended[at..at + len])
                .read_to_end(&mut raw)
                .unwrap();
            at += len;
        }
        let back: Vec<f64> = raw
            .chunks(8)
            .map(|c| f64::from_le_bytes(c.try_into().unwrap()))
            .collect();
        assert_eq!(back, vals);
    }
}
