//! How the parts of a decomposed assembly talk: a small set of collective
//! operations on byte buffers ([`Comm`]). [`Solo`] is one part (nothing
//! to exchange); [`Threads`] runs the parts as threads of one process (the
//! tests use it to check, without a system MPI, that the parts give the
//! result of the whole); the `mpi` feature adds an MPI implementation
//! (`efgdem::decomp::mpi`).
//!
//! Every operation is collective over the ranks involved and is called in
//! the same order on each, so no message needs a tag. Each rank counts
//! what it sends ([`Traffic`]).

use std::collections::VecDeque;
use std::sync::{Arc, Condvar, Mutex};
use std::time::Instant;

/// Bytes and messages a rank sent, and the time it spent communicating.
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize)]
pub struct Traffic {
    /// Bytes sent to other ranks.
    pub bytes: u64,
    /// Messages sent to other ranks (non-empty or not).
    pub messages: u64,
    /// Wall-clock seconds inside communication calls (waiting included).
    pub seconds: f64,
}

/// The collective operations the decomposition needs.
pub trait Comm: Send + Sync {
    /// This rank, `0..size()`.
    fn rank(&self) -> usize;
    /// Number of ranks.
    fn size(&self) -> usize;
    /// Each rank sends `send[r]` to rank `r` (its own entry stays here);
    /// returns what each rank sent to this one, by rank.
    fn all_to_all(&self, send: Vec<Vec<u8>>) -> Vec<Vec<u8>>;
    /// Point-to-point with known sizes: send each `(rank, bytes)`, fill
    /// each `(rank, buffer)` with what that rank sends here (exactly the
    /// buffer's length).
    fn exchange(&self, send: &[(usize, &[u8])], recv: &mut [(usize, &mut [u8])]);
    /// Every rank's `mine`, by rank.
    fn all_gather(&self, mine: &[u8]) -> Vec<Vec<u8>>;
    /// Traffic so far.
    fn traffic(&self) -> Traffic;
}

/// One rank: every collective is the identity.
#[derive(Debug, Default)]
pub struct Solo;

impl Comm for Solo {
    fn rank(&self) -> usize {
        0
    }
    fn size(&self) -> usize {
        1
    }
    fn all_to_all(&self, send: Vec<Vec<u8>>) -> Vec<Vec<u8>> {
        send
    }
    fn exchange(&self, _: &[(usize, &[u8])], _: &mut [(usize, &mut [u8])]) {}
    fn all_gather(&self, mine: &[u8]) -> Vec<Vec<u8>> {
        vec![mine.to_vec()]
    }
    fn traffic(&self) -> Traffic {
        Traffic::default()
    }
}

/// Mailboxes of a group of [`Threads`]: one FIFO queue per (from, to).
#[derive(Debug)]
struct Mailboxes {
    queues: Mutex<Vec<VecDeque<Vec<u8>>>>,
    arrived: Condvar,
    size: usize,
}

/// One rank of a group of ranks that are threads of this process.
#[derive(Debug)]
pub struct Threads {
    rank: usize,
    boxes: Arc<Mailboxes>,
    traffic: Mutex<Traffic>,
}

impl Threads {
    /// A group of `size` ranks (hand one to each thread).
    pub fn group(size: usize) -> Vec<Threads> {
        let boxes = Arc::new(Mailboxes {
            queues: Mutex::new(vec![VecDeque::new(); size * size]),
            arrived: Condvar::new(),
            size,
        });
        (0..size)
            .map(|rank| Threads {
                rank,
                boxes: boxes.clone(),
                traffic: Mutex::default(),
            })
            .collect()
    }

    fn post(&self, to: usize, bytes: Vec<u8>) {
        {
            let mut t = self.traffic.lock().unwrap();
            t.bytes += bytes.len() as u64;
            t.messages += 1;
        }
        let mut q = self.boxes.queues.lock().unwrap();
        q[self.rank * self.boxes.size + to].push_back(bytes);
        self.boxes.arrived.notify_all();
    }

    fn take(&self, from: usize) -> Vec<u8> {
        let mut q = self.boxes.queues.lock().unwrap();
        loop {
            if let Some(b) = q[from * self.boxes.size + self.rank].pop_front() {
                return b;
            }
            q = self.boxes.arrived.wait(q).unwrap();
        }
    }

    fn timed<T>(&self, f: impl FnOnce() -> T) -> T {
        let t0 = Instant::now();
        let r = f();
        self.traffic.lock().unwrap().seconds += t0.elapsed().as_secs_f64();
        r
    }
}

impl Comm for Threads {
    fn rank(&self) -> usize {
        self.rank
    }
    fn size(&self) -> usize {
        self.boxes.size
    }
    fn all_to_all(&self, mut send: Vec<Vec<u8>>) -> Vec<Vec<u8>> {
        self.timed(|| {
            let mine = std::mem::take(&mut send[self.rank]);
            for (to, b) in send.into_iter().enumerate() {
                if to != self.rank {
                    self.post(to, b);
                }
            }
            let mut mine = Some(mine);
            (0..self.size())
                .map(|r| {
                    if r == self.rank {
                        mine.take().unwrap_or_default()
                    } else {
                        self.take(r)
                    }
                })
                .collect()
        })
    }
    fn exchange(&self, send: &[(usize, &[u8])], recv: &mut [(usize, &mut [u8])]) {
        self.timed(|| {
            for (to, b) in send {
                self.post(*to, b.to_vec());
            }
            for (from, buf) in recv.iter_mut() {
                let b = self.take(*from);
                buf.copy_from_slice(&b);
            }
        })
    }
    fn all_gather(&self, mine: &[u8]) -> Vec<Vec<u8>> {
        self.all_to_all(vec![mine.to_vec(); self.size()])
    }
    fn traffic(&self) -> Traffic {
        *self.traffic.lock().unwrap()
    }
}

/// Little-endian packing of the records the ranks exchange.
#[derive(Debug, Default)]
pub struct Pack(pub Vec<u8>);

impl Pack {
    /// Append a `u8`.
    pub fn u8(&mut self, v: u8) {
        self.0.push(v);
    }
    /// Append a `u16`.
    pub fn u16(&mut self, v: u16) {
        self.0.extend_from_slice(&v.to_le_bytes());
    }
    /// Append a `u32`.
    pub fn u32(&mut self, v: u32) {
        self.0.extend_from_slice(&v.to_le_bytes());
    }
    /// Append a `u64`.
    pub fn u64(&mut self, v: u64) {
        self.0.extend_from_slice(&v.to_le_bytes());
    }
    /// Append an `f64` (its bits: exact).
    pub fn f64(&mut self, v: f64) {
        self.0.extend_from_slice(&v.to_le_bytes());
    }
    /// Append a [`Vec2`](crate::geom::Vec2).
    pub fn vec2(&mut self, v: crate::geom::Vec2) {
        self.f64(v.x);
        self.f64(v.y);
    }
}

/// Reading back what [`Pack`] wrote.
#[derive(Debug)]
pub struct Unpack<'a>(pub &'a [u8]);

impl Unpack<'_> {
    fn take<const N: usize>(&mut self) -> [u8; N] {
        let (a, b) = self.0.split_at(N);
        self.0 = b;
        a.try_into().expect("N bytes")
    }
    /// Anything left?
    pub fn is_empty(&self) -> bool {
        self.0.is_empty()
    }
    /// Next `u8`.
    pub fn u8(&mut self) -> u8 {
        self.take::<1>()[0]
    }
    /// Next `u16`.
    pub fn u16(&mut self) -> u16 {
        u16::from_le_bytes(self.take())
    }
    /// Next `u32`.
    pub fn u32(&mut self) -> u32 {
        u32::from_le_bytes(self.take())
    }
    /// Next `u64`.
    pub fn u64(&mut self) -> u64 {
        u64::from_le_bytes(self.take())
    }
    /// Next `f64`.
    pub fn f64(&mut self) -> f64 {
        f64::from_le_bytes(self.take())
    }
    /// Next [`Vec2`](crate::geom::Vec2).
    pub fn vec2(&mut self) -> crate::geom::Vec2 {
        let x = self.f64();
        crate::geom::Vec2::new(x, self.f64())
    }
}
