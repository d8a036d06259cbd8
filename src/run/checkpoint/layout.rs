//! The discs' and pairs' arrays of a checkpoint, stored raw (little
//! endian) after its header, so that a rank reads the elements it needs
//! without decoding the others: the arrays' lengths are in the header
//! ([`Table`]), their offsets follow from them.

use crate::dem::state::GranularState;
use crate::geom::Vec2;
use serde::{Deserialize, Serialize};
use std::io::{self, BufReader, Read, Seek, Write};

/// A value stored raw: its little-endian bytes.
pub(super) trait Raw: Copy {
    /// Bytes of one value.
    const SIZE: usize;
    fn put(self, out: &mut Vec<u8>);
    fn get(b: &[u8]) -> Self;
}

fn word<const N: usize>(b: &[u8]) -> [u8; N] {
    b[..N].try_into().expect("N bytes")
}

impl Raw for u32 {
    const SIZE: usize = 4;
    fn put(self, out: &mut Vec<u8>) {
        out.extend_from_slice(&self.to_le_bytes());
    }
    fn get(b: &[u8]) -> Self {
        u32::from_le_bytes(word(b))
    }
}

impl Raw for f64 {
    const SIZE: usize = 8;
    fn put(self, out: &mut Vec<u8>) {
        out.extend_from_slice(&self.to_le_bytes());
    }
    fn get(b: &[u8]) -> Self {
        f64::from_le_bytes(word(b))
    }
}

impl Raw for Vec2 {
    const SIZE: usize = 16;
    fn put(self, out: &mut Vec<u8>) {
        self.x.put(out);
        self.y.put(out);
    }
    fn get(b: &[u8]) -> Self {
        Vec2::new(f64::get(b), f64::get(&b[8..]))
    }
}

impl Raw for [u32; 2] {
    const SIZE: usize = 8;
    fn put(self, out: &mut Vec<u8>) {
        self[0].put(out);
        self[1].put(out);
    }
    fn get(b: &[u8]) -> Self {
        [u32::get(b), u32::get(&b[4..])]
    }
}

/// The raw arrays, in their order in the file: the discs' (by slot of
/// the whole), then the pairs' (sorted by `(i, j)`).
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub(super) enum Col {
    /// Ids (u32).
    Id,
    /// Positions (2 × f64).
    Pos,
    /// Velocities.
    Vel,
    /// Rotations (f64).
    Theta,
    /// Spins.
    Omega,
    /// Forces (2 × f64).
    Force,
    /// Moments (f64).
    Torque,
    /// Positions at the last rebuild (2 × f64), if stored.
    RefPos,
    /// Pairs `(i, j)`, `i < j` (2 × u32).
    Pairs,
    /// Shear histories (f64).
    Shear,
    /// Rolling-spring histories (f64), if stored.
    Roll,
}

const COLS: [Col; 11] = [
    Col::Id,
    Col::Pos,
    Col::Vel,
    Col::Theta,
    Col::Omega,
    Col::Force,
    Col::Torque,
    Col::RefPos,
    Col::Pairs,
    Col::Shear,
    Col::Roll,
];

/// The raw arrays' lengths: discs, pairs, and whether the optional ones
/// are stored (in the header).
#[derive(Serialize, Deserialize, Clone, Copy, Debug, PartialEq)]
pub(super) struct Table {
    /// Discs of the whole assembly.
    pub discs: u64,
    /// Listed disc–disc pairs.
    pub pairs: u64,
    /// The Verlet reference positions are stored.
    pub ref_pos: bool,
    /// The rolling histories are stored.
    pub roll: bool,
}

impl Table {
    /// The lengths of the arrays of `s`.
    pub fn of(s: &GranularState) -> Table {
        Table {
            discs: s.id.len() as u64,
            pairs: s.pairs.len() as u64,
            ref_pos: !s.ref_pos.is_empty(),
            roll: !s.roll.is_empty(),
        }
    }

    /// Elements of `c` and bytes of each.
    fn shape(&self, c: Col) -> (u64, u64) {
        let (n, m) = (self.discs, self.pairs);
        match c {
            Col::Id => (n, 4),
            Col::Pos | Col::Vel | Col::Force => (n, 16),
            Col::Theta | Col::Omega | Col::Torque => (n, 8),
            Col::RefPos => (n * self.ref_pos as u64, 16),
            Col::Pairs | Col::Shear => (m, 8),
            Col::Roll => (m * self.roll as u64, 8),
        }
    }

    /// Elements of `c`.
    pub fn len(&self, c: Col) -> usize {
        self.shape(c).0 as usize
    }

    /// Bytes of all the arrays; `None` beyond `u64` (a damaged header).
    pub fn bytes(&self) -> Option<u64> {
        COLS.iter().try_fold(0u64, |sum, &c| {
            let (n, size) = self.shape(c);
            sum.checked_add(n.checked_mul(size)?)
        })
    }

    /// Where `c` starts, from the start of the arrays.
    fn offset(&self, c: Col) -> u64 {
        COLS.iter()
            .take_while(|&&k| k != c)
            .map(|&k| self.shape(k).0 * self.shape(k).1)
            .sum()
    }
}

/// The raw arrays of `s`, moved out of it (left empty there).
pub(super) fn take(s: &mut GranularState) -> GranularState {
    use std::mem::take;
    GranularState {
        id: take(&mut s.id),
        pos: take(&mut s.pos),
        vel: take(&mut s.vel),
        theta: take(&mut s.theta),
        omega: take(&mut s.omega),
        force: take(&mut s.force),
        torque: take(&mut s.torque),
        ref_pos: take(&mut s.ref_pos),
        pairs: take(&mut s.pairs),
        shear: take(&mut s.shear),
        roll: take(&mut s.roll),
        ..GranularState::default()
    }
}

/// Put the raw arrays `a` ([`take`]) back into `s`.
pub(super) fn put_back(s: &mut GranularState, a: GranularState) {
    (s.id, s.pos, s.vel, s.theta) = (a.id, a.pos, a.vel, a.theta);
    (s.omega, s.force, s.torque) = (a.omega, a.force, a.torque);
    (s.ref_pos, s.pairs, s.shear, s.roll) = (a.ref_pos, a.pairs, a.shear, a.roll);
}

/// Write `v` raw, a block at a time.
fn put_all<T: Raw>(v: &[T], w: &mut impl Write) -> io::Result<()> {
    let mut buf = Vec::with_capacity(1 << 16);
    for chunk in v.chunks((1 << 16) / T::SIZE) {
        buf.clear();
        chunk.iter().for_each(|&x| x.put(&mut buf));
        w.write_all(&buf)?;
    }
    Ok(())
}

/// Write the raw arrays of `a` ([`take`]) in their order.
pub(super) fn write(a: &GranularState, w: &mut impl Write) -> io::Result<()> {
    put_all(&a.id, w)?;
    put_all(&a.pos, w)?;
    put_all(&a.vel, w)?;
    put_all(&a.theta, w)?;
    put_all(&a.omega, w)?;
    put_all(&a.force, w)?;
    put_all(&a.torque, w)?;
    put_all(&a.ref_pos, w)?;
    put_all(&a.pairs, w)?;
    put_all(&a.shear, w)?;
    put_all(&a.roll, w)
}

/// The raw arrays of a checkpoint file, read element by element at the
/// indices asked for (through a buffer: indices close together cost one
/// read).
pub(super) struct Arrays<R> {
    file: BufReader<R>,
    /// Where the arrays start in the file.
    base: u64,
    /// Where the reader is.
    at: u64,
    pub table: Table,
}

impl<R: Read + Seek> Arrays<R> {
    /// The arrays of `table` at `base` in `file`, which is at `at`.
    pub fn new(file: BufReader<R>, at: u64, base: u64, table: Table) -> Self {
        Arrays {
            file,
            base,
            at,
            table,
        }
    }

    /// `f(i, value)` for each index `i` of `idx` (ascending) of `c`.
    pub fn each<T: Raw>(
        &mut self,
        c: Col,
        idx: impl IntoIterator<Item = usize>,
        mut f: impl FnMut(usize, T),
    ) -> io::Result<()> {
        let (len, size) = self.table.shape(c);
        debug_assert_eq!(size, T::SIZE as u64, "{c:?}");
        let start = self.base + self.table.offset(c);
        let mut b = [0u8; 16];
        for i in idx {
            assert!((i as u64) < len, "{c:?}[{i}] of {len}");
            let to = start + i as u64 * size;
            self.file.seek_relative(to as i64 - self.at as i64)?;
            self.file.read_exact(&mut b[..T::SIZE])?;
            self.at = to + size;
            f(i, T::get(&b));
        }
        Ok(())
    }

    /// The elements of `c` at `idx` (ascending).
    pub fn pick<T: Raw>(&mut self, c: Col, idx: &[u32]) -> io::Result<Vec<T>> {
        let mut v = Vec::with_capacity(idx.len());
        self.each(c, idx.iter().map(|&i| i as usize), |_, x| v.push(x))?;
        Ok(v)
    }

    /// Every element of `c`.
    pub fn all<T: Raw>(&mut self, c: Col) -> io::Result<Vec<T>> {
        let n = self.table.len(c);
        let mut v = Vec::new();
        v.try_reserve_exact(n).map_err(io::Error::other)?;
        self.each(c, 0..n, |_, x| v.push(x))?;
        Ok(v)
    }

    /// Every array, as [`take`] leaves them.
    pub fn read_all(&mut self) -> io::Result<GranularState> {
        Ok(GranularState {
            id: self.all(Col::Id)?,
            pos: self.all(Col::Pos)?,
            vel: self.all(Col::Vel)?,
            theta: self.all(Col::Theta)?,
            omega: self.all(Col::Omega)?,
            force: self.all(Col::Force)?,
            torque: self.all(Col::Torque)?,
            ref_pos: self.all(Col::RefPos)?,
            pairs: self.all(Col::Pairs)?,
            shear: self.all(Col::Shear)?,
            roll: self.all(Col::Roll)?,
            ..GranularState::default()
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Arrays written raw are read back, whole and element by element at
    /// the offsets the table gives.
    #[test]
    fn raw_arrays_are_read_back_where_the_table_puts_them() {
        let n = 5;
        let v = |k: usize| Vec2::new(k as f64 + 0.25, -(k as f64));
        let mut s = GranularState {
            id: vec![3, 1, 4, 0, 2],
            pos: (0..n).map(v).collect(),
            vel: (0..n).map(|k| v(k + 10)).collect(),
            theta: (0..n).map(|k| k as f64 * 0.5).collect(),
            omega: (0..n).map(|k| -(k as f64)).collect(),
            force: (0..n).map(|k| v(k + 20)).collect(),
            torque: (0..n).map(|k| k as f64 * 3.0).collect(),
            pairs: vec![[0, 2], [1, 4], [3, 4]],
            shear: vec![0.5, -1.5, 2.5],
            roll: vec![1e-3, 2e-3, 3e-3],
            ..GranularState::default()
        };
        let arrays = take(&mut s);
        let t = Table::of(&arrays);
        let mut bytes = vec![7u8; 3];
        write(&arrays, &mut bytes).unwrap();
        assert_eq!(bytes.len() as u64, 3 + t.bytes().unwrap());
        let file = BufReader::new(io::Cursor::new(bytes));
        let mut a = Arrays::new(file, 0, 3, t);
        let picked: Vec<f64> = a.pick(Col::Omega, &[1, 4]).unwrap();
        assert_eq!(picked, [-1.0, -4.0]);
        let pairs: Vec<[u32; 2]> = a.pick(Col::Pairs, &[2]).unwrap();
        assert_eq!(pairs, [[3, 4]]);
        let back = a.read_all().unwrap();
        assert!(back == arrays);
        put_back(&mut s, back);
        assert_eq!(s.id, [3, 1, 4, 0, 2]);
    }
}
