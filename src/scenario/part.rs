//! A rank's part of a granular scenario's assembly, built without the
//! whole: the scenario's discs are passed over a few times (a generated
//! packing made again each time, disc by disc, never listed; rows read
//! where they are), keeping each time only what the pass needs — the
//! count, sums and the few discs that decide the time step, then the
//! sample of centres that cuts the regions and the discs that cross a
//! wall, then the part's own discs. The checks of the start state are
//! those of the whole, with the same outcome and message on every rank:
//! the overlapping pairs are found on each part (a pair with a disc of the
//! region lies within the part) and agreed over the ranks. A rank that
//! restarts from a checkpoint makes the first pass only
//! ([`PartSkeleton`]), then the discs the checkpoint says it holds.

use super::build::{
    BuildFor, START_OVERLAP_TOL, assembly, bad, default_skin, disc_of, disc_rows, lattice_of,
    material_index, overlap_checks, pairs_refusal, preparation, reserve, spec, start_limits,
    time_step, wall_overlap, wall_refusal,
};
use super::granular::{DiscsSpec, DiscsTable, GranularSpec, centroid, check_wall_speeds, walls};
use super::{Invalid, Scenario};
use crate::decomp::comm::{Pack, Unpack};
use crate::decomp::{Comm, Cut, sample_stride};
use crate::dem::Granular;
use crate::dem::packing::{DiscRow, lattice_each, overlapping_pairs};
use crate::dem::particles::{Particles, SlotIndex};
use crate::geom::Vec2;
use std::borrow::Cow;

/// Where the whole's discs come from, pass after pass.
enum Source<'a> {
    /// A packing used as generated: made again at each pass.
    Lattice(&'a DiscsTable),
    /// Discs given or prepared as rows.
    Rows(Cow<'a, [DiscRow]>),
}

/// One disc of the whole assembly as a pass sees it.
struct Disc {
    /// Its slot (and id) in the whole.
    id: usize,
    pos: Vec2,
    r: f64,
    material: u16,
    mass: f64,
}

/// The disc source of `sc` for `purpose`.
fn source<'a>(sc: &'a Scenario, purpose: BuildFor<'a>) -> Result<Source<'a>, Invalid> {
    let generated = match &spec(sc)?.discs {
        DiscsSpec::Table(t) if t.csv.is_none() && preparation(sc).is_none() => Some(t),
        _ => None,
    };
    Ok(match (generated, purpose) {
        (Some(t), _) => Source::Lattice(t),
        (None, BuildFor::Prepared(rows)) if preparation(sc).is_some() => {
            Source::Rows(Cow::Borrowed(rows))
        }
        (None, _) => Source::Rows(Cow::Owned(disc_rows(sc, purpose)?)),
    })
}

/// Hand `f` each disc of the whole assembly (those inside `[granular]
/// keep`), in slot order; the first that cannot be made is the error (as
/// the whole's build finds it). Returns how many discs the scenario
/// describes, inside the circle or not.
fn each(sc: &Scenario, src: &Source, f: &mut dyn FnMut(&Disc)) -> Result<usize, Invalid> {
    let g = spec(sc)?;
    let default_mat = material_index(sc, &g.material, "granular.material")?;
    let keep = g.keep;
    let (mut seen, mut n, mut failed) = (0usize, 0usize, None);
    let mut put = |row: &DiscRow| {
        seen += 1;
        if failed.is_some() || keep.is_some_and(|k| !k.holds(row.pos, row.r)) {
            return;
        }
        match disc_of(sc, n, row, default_mat) {
            Ok((material, mass, _)) => {
                let (pos, r, id) = (row.pos, row.r, n);
                f(&Disc {
                    id,
                    pos,
                    r,
                    material,
                    mass,
                });
                n += 1;
            }
            Err(e) => failed = Some(e),
        }
    };
    match src {
        Source::Lattice(t) => {
            let l = lattice_of(t)?;
            let mut one = |pos, r| {
                put(&DiscRow {
                    pos,
                    r,
                    material: None,
                })
            };
            let (lat, radius, count) = (l.lattice, l.radius, t.count);
            lattice_each(
                lat, l.lo, l.hi, radius, count, l.gap, l.jitter, t.seed, &mut one,
            )
            .map_err(|e| bad("granular.discs", e))?;
        }
        Source::Rows(rows) => rows.iter().for_each(&mut put),
    }
    match failed {
        Some(e) => Err(e),
        None => Ok(seen),
    }
}

/// What the first pass learns of the whole: its count, the sum of its
/// centres, its largest radius, and the discs that decide its critical
/// step and smallest radius (the first three, the lightest, the first of
/// each material, the smallest; [`Granular::critical_step`] of these is
/// the whole's).
#[derive(Default)]
struct Whole {
    n: usize,
    sum: Vec2,
    max_r: f64,
    /// `(id, mass, radius, material)` of the discs kept.
    few: Vec<(usize, f64, f64, u16)>,
    lightest: Option<(usize, f64, f64, u16)>,
    smallest: Option<(usize, f64, f64, u16)>,
    materials: Vec<bool>,
}

impl Whole {
    fn add(&mut self, d: &Disc) {
        let e = (d.id, d.mass, d.r, d.material);
        self.n += 1;
        self.sum += d.pos;
        self.max_r = self.max_r.max(d.r);
        let m = d.material as usize;
        if self.materials.len() <= m {
            self.materials.resize(m + 1, false);
        }
        let first_of_material = !std::mem::replace(&mut self.materials[m], true);
        if d.id < 3 || first_of_material {
            self.few.push(e);
        }
        if self.lightest.is_none_or(|l| d.mass.total_cmp(&l.1).is_lt()) {
            self.lightest = Some(e);
        }
        if self.smallest.is_none_or(|s| d.r < s.2) {
            self.smallest = Some(e);
        }
    }

    /// The discs kept, in slot order: those of the whole that decide its
    /// critical step and smallest radius.
    fn discs(&self) -> Particles {
        let mut all = self.few.clone();
        all.extend(self.lightest.iter().chain(&self.smallest));
        all.sort_by_key(|e| e.0);
        all.dedup_by_key(|e| e.0);
        Particles {
            pos: vec![Vec2::ZERO; all.len()],
            mass: all.iter().map(|e| e.1).collect(),
            radius: all.iter().map(|e| e.2).collect(),
            material: all.iter().map(|e| e.3).collect(),
            ..Particles::default()
        }
    }
}

/// Discs crossing each wall: how many, and the first five `(id, overlap)`.
type WallHits = Vec<(usize, Vec<(usize, f64)>)>;

/// The whole's first pass and the assembly without discs: walls, laws,
/// time step (checked on the discs that decide it) and skin.
fn skeleton(sc: &Scenario, src: &Source) -> Result<(Granular, Whole), Invalid> {
    let g = spec(sc)?;
    let mut whole = Whole::default();
    let seen = each(sc, src, &mut |d| whole.add(d))?;
    if whole.n == 0 && seen > 0 && g.keep.is_some() {
        return Err(bad(
            "granular.keep",
            format!("none of the {seen} discs lies inside the circle"),
        ));
    }
    let walls = walls(sc, centroid(whole.sum, whole.n))?;
    let mut gr = assembly(sc, Particles::default(), walls)?;
    // the time step and its checks from the discs that decide them
    let mut few = gr.with_discs(whole.discs());
    gr.dt = time_step(sc, &few)?;
    few.dt = gr.dt;
    check_wall_speeds(sc, &few)?;
    start_limits(sc, &few)?;
    gr.set_skin(g.skin.unwrap_or(default_skin(whole.max_r)));
    Ok((gr, whole))
}

/// A rank's part of the assembly of `sc` and the ranks' regions (see the
/// [module docs](self)); the whole's start positions are kept only where
/// they serve (rank 0's frames).
pub(super) fn granular(
    sc: &Scenario,
    purpose: BuildFor,
    comm: &dyn Comm,
) -> Result<(Granular, Cut), Invalid> {
    let src = source(sc, purpose)?;
    let (mut gr, whole) = skeleton(sc, &src)?;
    let checks = overlap_checks(sc, purpose)?;
    let skin = gr.grid.skin;
    // the sample that cuts the regions, and the discs crossing a wall
    let stride = sample_stride(whole.n);
    let mut sample = Vec::with_capacity(whole.n.div_ceil(stride));
    let crossing = checks == Some(false);
    let mut hits: WallHits = vec![(0, Vec::new()); gr.walls.len() * crossing as usize];
    each(sc, &src, &mut |d| {
        if d.id % stride == 0 {
            sample.push(d.pos);
        }
        for ((count, first), w) in hits.iter_mut().zip(&gr.walls) {
            let o = wall_overlap(w, d.pos, d.r);
            if o > START_OVERLAP_TOL * d.r {
                *count += 1;
                if first.len() < 5 {
                    first.push((d.id, o));
                }
            }
        }
    })?;
    let cut = Cut::from_sample(&sample, whole.n, whole.max_r, skin, comm.size());
    drop(sample);
    let (particles, start) = discs_of_part(sc, &src, &cut, comm.rank())?;
    if checks == Some(false) {
        agree_on_pairs(&particles, &cut, comm)?;
    }
    if let Some((wi, (count, first))) = hits.iter().enumerate().find(|(_, h)| h.0 > 0) {
        return Err(wall_refusal(wi, &gr.walls[wi].name, *count, first));
    }
    gr.particles = particles;
    gr.set_start(start);
    Ok((gr, cut))
}

/// What a rank restarting from a checkpoint builds of a granular
/// scenario before it knows its discs ([`Scenario::part_skeleton`]): the
/// assembly without discs, the whole's disc count and largest radius;
/// then the discs it holds, by id ([`discs`](Self::discs)). The checks of
/// the start state are not made again (the checkpoint's run passed them).
pub struct PartSkeleton<'a> {
    sc: &'a Scenario,
    src: Source<'a>,
    /// The model without discs (indexed among the whole's ids): walls,
    /// laws, time step, skin, steps.
    pub model: crate::model::Model,
    /// Discs of the whole assembly.
    pub n_total: usize,
    /// Largest radius of the whole assembly.
    pub max_radius: f64,
}

/// [`PartSkeleton`] of `sc` (a plain granular scenario).
pub(super) fn part_skeleton<'a>(
    sc: &'a Scenario,
    purpose: BuildFor<'a>,
) -> Result<PartSkeleton<'a>, Invalid> {
    let src = source(sc, purpose)?;
    let (mut gr, whole) = skeleton(sc, &src)?;
    // the whole's ids, none held (the probes are bound to them)
    gr.particles.slot = SlotIndex::of_part(whole.n, &[]);
    let model = super::build::part_model(sc, gr)?;
    Ok(PartSkeleton {
        sc,
        src,
        model,
        n_total: whole.n,
        max_radius: whole.max_r,
    })
}

impl PartSkeleton<'_> {
    /// The discs `ids` (ascending, of the whole) as built, in id order,
    /// at the scenario's velocity, indexed among the whole's; and the
    /// whole's start positions by id if `start` (else none).
    pub fn discs(
        &self,
        ids: &[u32],
        start: bool,
    ) -> Result<(Particles, Vec<Vec2>), super::ScenarioError> {
        self.discs_by_id(ids, start)
            .map_err(|e| self.sc.located(vec![e]))
    }

    fn discs_by_id(&self, ids: &[u32], start: bool) -> Result<(Particles, Vec<Vec2>), Invalid> {
        let sc = self.sc;
        let g = spec(sc)?;
        let mut p = Particles::default();
        reserve(&mut p, ids.len())?;
        let mut all = Vec::new();
        if start {
            all.reserve_exact(self.n_total);
        }
        let mut next = ids.iter().copied().peekable();
        each(sc, &self.src, &mut |d| {
            if start {
                all.push(d.pos);
            }
            if next.next_if_eq(&(d.id as u32)).is_some() {
                put_disc(sc, g, &mut p, d);
            }
        })?;
        if let Some(id) = next.next() {
            return Err(bad(
                "granular.discs",
                format!("the scenario has no disc {id} (of the checkpoint)"),
            ));
        }
        p.slot = SlotIndex::of_part(self.n_total, &p.id);
        Ok((p, all))
    }
}

/// Add disc `d` of the whole to the part `p` as the whole's build makes
/// it, with the whole's id, at the scenario's velocity.
fn put_disc(sc: &Scenario, g: &GranularSpec, p: &mut Particles, d: &Disc) {
    let density = sc.material[d.material as usize].density;
    p.push(d.pos, d.r, density, g.thickness, d.material);
    let j = p.len() - 1;
    p.vel[j] = g.velocity.map(Vec2::from).unwrap_or(Vec2::ZERO);
    // the whole's numbering
    p.id[j] = d.id as u32;
}

/// The discs `cut` keeps for rank `me` (counted, then made), with the
/// whole's ids, at the scenario's velocity; and the whole's start
/// positions by id where they serve (else none).
fn discs_of_part(
    sc: &Scenario,
    src: &Source,
    cut: &Cut,
    me: usize,
) -> Result<(Particles, Vec<Vec2>), Invalid> {
    let g = spec(sc)?;
    let mut held = 0;
    each(sc, src, &mut |d| held += cut.holds(d.pos, me) as usize)?;
    let mut p = Particles::default();
    reserve(&mut p, held)?;
    let mut start = Vec::new();
    let keep_start = wants_start(sc, me);
    if keep_start {
        start.reserve_exact(cut.n_total);
    }
    each(sc, src, &mut |d| {
        if keep_start {
            start.push(d.pos);
        }
        if cut.holds(d.pos, me) {
            put_disc(sc, g, &mut p, d);
        }
    })?;
    p.slot = SlotIndex::of_part(cut.n_total, &p.id);
    Ok((p, start))
}

/// Whether rank `me` keeps the whole's start positions: rank 0 when it
/// writes frames (their displacements; a probe of a disc's displacement
/// is one of a coupled run, which is not built in parts).
fn wants_start(sc: &Scenario, me: usize) -> bool {
    me == 0 && sc.output.vtk_every != 0
}

/// The pairs of discs of the whole that overlap at the start (collective):
/// each rank finds those whose lower disc its region holds (the other
/// disc is within the part's reach), and every rank refuses them all, as
/// the whole's check lists them.
fn agree_on_pairs(p: &Particles, cut: &Cut, comm: &dyn Comm) -> Result<(), Invalid> {
    let me = comm.rank();
    // the part's slots are in id order: a pair's lower slot is its lower id
    let mine: Vec<(usize, usize, f64)> = overlapping_pairs(&p.pos, &p.radius, START_OVERLAP_TOL)
        .into_iter()
        .filter(|&(a, _, _)| cut.regions.owner(p.pos[a]) == me)
        .map(|(a, b, d)| (p.id[a] as usize, p.id[b] as usize, d))
        .collect();
    let mut b = Pack::default();
    b.u64(mine.len() as u64);
    for &(x, y, d) in mine.iter().take(5) {
        b.u64(x as u64);
        b.u64(y as u64);
        b.f64(d);
    }
    let (mut total, mut first) = (0, Vec::new());
    for got in comm.all_gather(&b.0) {
        let mut u = Unpack(&got);
        total += u.u64() as usize;
        while !u.is_empty() {
            first.push((u.u64() as usize, u.u64() as usize, u.f64()));
        }
    }
    if total == 0 {
        return Ok(());
    }
    first.sort_by_key(|&(x, y, _)| (x, y));
    first.truncate(5);
    Err(pairs_refusal(total, &first))
}
