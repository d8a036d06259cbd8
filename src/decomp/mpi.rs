//! The [`Comm`] operations over MPI (the `mpi` cargo feature; rsmpi on a
//! system MPI such as OpenMPI or MPICH).

use super::comm::{Comm, Traffic};
use mpi::datatype::{Partition, PartitionMut};
use mpi::environment::{Threading, Universe};
use mpi::topology::SimpleCommunicator;
use mpi::traits::*;
use std::sync::Mutex;
use std::time::Instant;

/// The ranks of `MPI_COMM_WORLD`. Made once per process ([`Mpi::init`]);
/// MPI is finalised when it is dropped.
pub struct Mpi {
    rank: usize,
    size: usize,
    /// Every MPI call holds this lock (MPI is initialised with
    /// `MPI_THREAD_SERIALIZED`: calls from any thread, never two at once).
    inner: Mutex<Inner>,
}

struct Inner {
    world: SimpleCommunicator,
    traffic: Traffic,
    // declared last: dropped (MPI_Finalize) after the communicator
    _universe: Universe,
}

// SAFETY: the communicator is a handle that MPI lets any thread use when
// MPI runs at `MPI_THREAD_SERIALIZED` or above, provided no two calls
// overlap; every use goes through the mutex of `Mpi`.
unsafe impl Send for Inner {}

impl Mpi {
    /// Initialise MPI; `None` when it already was in this process, or
    /// when the library cannot give serialised thread support. On several
    /// ranks a panic then aborts the job ([`abort_on_panic`]).
    pub fn init() -> Option<Mpi> {
        let (universe, level) = mpi::initialize_with_threading(Threading::Serialized)?;
        if level < Threading::Serialized {
            return None;
        }
        let world = universe.world();
        if world.size() > 1 {
            abort_on_panic();
        }
        Some(Mpi {
            rank: world.rank() as usize,
            size: world.size() as usize,
            inner: Mutex::new(Inner {
                world,
                traffic: Traffic::default(),
                _universe: universe,
            }),
        })
    }

    fn with<T>(&self, f: impl FnOnce(&SimpleCommunicator, &mut Traffic) -> T) -> T {
        let mut g = self.inner.lock().unwrap_or_else(|e| e.into_inner());
        let t0 = Instant::now();
        let Inner { world, traffic, .. } = &mut *g;
        let r = f(world, traffic);
        traffic.seconds += t0.elapsed().as_secs_f64();
        r
    }
}

/// Make a panic end the whole job: the panic is printed (the default hook),
/// then every rank is stopped (`MPI_Abort`). Without it the panicking rank
/// would unwind into `MPI_Finalize` while the others wait for it in a
/// collective, and the job would hang.
fn abort_on_panic() {
    let default = std::panic::take_hook();
    std::panic::set_hook(Box::new(move |info| {
        default(info);
        if !mpi::environment::is_finalized() {
            // the code Rust gives a process that panicked
            SimpleCommunicator::world().abort(101);
        }
    }));
}

/// MPI counts and displacements are `i32`: a buffer of 2 GiB or more to
/// one rank is beyond what one call can move.
fn count(n: usize) -> i32 {
    i32::try_from(n).expect("an MPI message of less than 2 GiB")
}

fn displacements(counts: &[i32]) -> Vec<i32> {
    counts
        .iter()
        .scan(0i32, |at, &c| {
            let d = *at;
            *at += c;
            Some(d)
        })
        .collect()
}

/// A buffer of at least one byte. An empty `Vec<u8>` points at address 1,
/// which OpenMPI reads as `MPI_IN_PLACE`: a collective would then use its
/// receive buffer as the data sent (or refuse the call).
fn nonempty(mut v: Vec<u8>) -> Vec<u8> {
    if v.is_empty() {
        v.push(0);
    }
    v
}

/// The received bytes cut into one vector per rank.
fn split(buf: &[u8], counts: &[i32]) -> Vec<Vec<u8>> {
    let mut at = 0;
    counts
        .iter()
        .map(|&c| {
            let v = buf[at..at + c as usize].to_vec();
            at += c as usize;
            v
        })
        .collect()
}

impl Comm for Mpi {
    fn rank(&self) -> usize {
        self.rank
    }
    fn size(&self) -> usize {
        self.size
    }
    fn all_to_all(&self, send: Vec<Vec<u8>>) -> Vec<Vec<u8>> {
        let me = self.rank;
        self.with(|world, t| {
            let scount: Vec<i32> = send.iter().map(|b| count(b.len())).collect();
            let mut rcount = vec![0i32; send.len()];
            world.all_to_all_into(&scount[..], &mut rcount[..]);
            let flat = nonempty(send.concat());
            let mut got = nonempty(vec![0u8; rcount.iter().map(|&c| c as usize).sum()]);
            {
                let sd = displacements(&scount);
                let rd = displacements(&rcount);
                let s = Partition::new(&flat[..], &scount[..], &sd[..]);
                let mut r = PartitionMut::new(&mut got[..], &rcount[..], &rd[..]);
                world.all_to_all_varcount_into(&s, &mut r);
            }
            let others = send.iter().enumerate().filter(|(r, _)| *r != me);
            t.bytes += others.clone().map(|(_, b)| b.len() as u64).sum::<u64>();
            t.messages += others.count() as u64;
            split(&got, &rcount)
        })
    }
    fn exchange(&self, send: &[(usize, &[u8])], recv: &mut [(usize, &mut [u8])]) {
        self.with(|world, t| {
            mpi::request::scope(|scope| {
                let mut reqs = Vec::with_capacity(send.len() + recv.len());
                for (from, buf) in recv.iter_mut() {
                    let p = world.process_at_rank(*from as i32);
                    reqs.push(p.immediate_receive_into(scope, &mut buf[..]));
                }
                for (to, buf) in send {
                    let p = world.process_at_rank(*to as i32);
                    reqs.push(p.immediate_send(scope, &buf[..]));
                    t.bytes += buf.len() as u64;
                    t.messages += 1;
                }
                for r in reqs {
                    r.wait();
                }
            });
        })
    }
    fn all_gather(&self, mine: &[u8]) -> Vec<Vec<u8>> {
        let size = self.size;
        self.with(|world, t| {
            let mut counts = vec![0i32; size];
            world.all_gather_into(&count(mine.len()), &mut counts[..]);
            let displs = displacements(&counts);
            let mut got = nonempty(vec![0u8; counts.iter().map(|&c| c as usize).sum()]);
            let one = nonempty(Vec::new());
            let mine = if mine.is_empty() { &one[..0] } else { mine };
            {
                let mut r = PartitionMut::new(&mut got[..], &counts[..], &displs[..]);
                world.all_gather_varcount_into(mine, &mut r);
            }
            t.bytes += (mine.len() * (size - 1)) as u64;
            t.messages += size as u64 - 1;
            split(&got, &counts)
        })
    }
    fn traffic(&self) -> Traffic {
        self.inner.lock().unwrap_or_else(|e| e.into_inner()).traffic
    }
}
