//! The discrete-element granular assembly (§2.3, §3 and Table 1, DE column).
//!
//! [`Granular`] holds the discs ([`particles`]), the rigid walls
//! ([`walls`]), the contact list with its shear histories ([`broadphase`])
//! and the contact laws ([`contact`]). One time step is a sequence of
//! public phases, so that a coupled loop can add forces between them:
//!
//! ```text
//! prepare_contacts()        rebuild the Verlet list if a disc moved > skin/2
//! compute_contact_forces()  force/torque := Σ contact forces (disc–disc, disc–wall)
//! ... add external forces:  add_external_force(slot, f, point)
//! integrate()               gravity, damping, central difference (Eqs. 50–54), walls move
//! ```
//! [`Granular::step`] runs the three as one [`sweep`] over the discs (each
//! disc advances as soon as its contacts are summed; bitwise the same
//! result).
//!
//! For the coupling: build with [`Granular::new`] (the scenario does it
//! for a `[granular]` section), then per step call `prepare_contacts`,
//! `compute_contact_forces`, add the disc–body-boundary contact forces
//! with [`Granular::add_external_force`] (slot, force, contact point: the
//! moment follows from the point), then `integrate`. Discs live in
//! *slots* that are renumbered in space-filling order from time to time
//! inside `prepare_contacts`; the scenario's disc number `id` (0-based) is
//! stable, `slot(id)` finds its slot and `particles.id[slot]` goes back. A
//! coupling that keeps its own shear histories for disc–segment contacts
//! should key them by disc `id`, not slot. Disc–disc and disc–wall
//! histories are kept here, keyed by slot pairs `(i < j)` / `(disc, wall)`
//! and remapped on renumbering.

pub mod bonds;
pub mod broadphase;
pub mod clumps;
pub mod contact;
pub mod critical;
pub mod integrate;
pub mod measure;
pub mod packing;
pub mod particles;
pub mod state;
pub mod sweep;
pub mod walls;

use crate::geom::Vec2;
use crate::geom::exact_sum::ExactSum;

/// `efgdem check` and `run` warn above this fraction of the critical step
/// ([`Granular::critical_step`]).
pub const DT_WARN: f64 = 0.8;

/// Default time step, as a fraction of the critical step
/// ([`Granular::critical_step`]), when a scenario gives none.
pub const DT_SAFETY: f64 = 0.5;
use bonds::Bonds;
use broadphase::{ContactList, NeighbourGrid};
use clumps::Clumps;
use contact::{ContactLaw, effective_mass, normal_between};
use particles::Particles;
use walls::Wall;

/// Errors of the DEM.
#[derive(Debug, thiserror::Error)]
pub enum DemError {
    /// The scenario is valid TOML but cannot be built (e.g. a bad disc file).
    #[error("{0}")]
    Input(String),
    /// An i/o error.
    #[error("i/o: {0}")]
    Io(#[from] std::io::Error),
    /// A disc position or velocity became non-finite.
    #[error(
        "the assembly became unstable at step {step} (non-finite disc state); reduce dt (critical step {dt_crit:e})"
    )]
    Unstable {
        /// Steps done when it was detected.
        step: usize,
        /// The critical step of the contacts in use
        /// ([`Granular::critical_step`]).
        dt_crit: f64,
    },
    /// A preparation ([`packing::settle_in_box`], [`packing::grow_in_box`])
    /// was stopped by its watch.
    #[error("the preparation was stopped after {step} steps")]
    Stopped {
        /// Steps done.
        step: usize,
    },
}

/// A closed disc–wall contact ([`Granular::wall_contact`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WallContact {
    /// Contact point on the wall.
    pub point: Vec2,
    /// Unit normal from the disc's centre towards the wall.
    pub normal: Vec2,
    /// Overlap δ.
    pub overlap: f64,
    /// Elastic normal force `k_n δ`.
    pub elastic: f64,
    /// Total normal force with the dashpot (clamped at zero).
    pub total: f64,
}

/// What one disc–wall pair adds to its wall's totals
/// ([`Granular::wall_terms`]).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct WallTerm {
    /// Slot of the disc.
    pub disc: u32,
    /// Index of the wall.
    pub wall: u32,
    /// Contact force on the disc (the wall gets its opposite).
    pub f: Vec2,
    /// The disc touches a wall that follows the state (servo, strain
    /// rate): it counts in the wall's contacts, stiffness and damping.
    pub counted: bool,
    /// The pair's `k_n` (when counted).
    pub kn: f64,
    /// The pair's normal dashpot `c_n` (when counted).
    pub cn: f64,
}

/// The disc check done inside [`Granular::step`] (no extra pass over the
/// discs): at which step, with which bound, and whether every disc passed.
#[derive(Debug, Clone, Copy, PartialEq)]
struct StepCheck {
    step: usize,
    radii_per_step: f64,
    clean: bool,
}

/// Damping that acts on each disc's motion rather than in the contacts.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum BodyDamping {
    /// No damping of the discs' motion (contact dashpots only).
    #[default]
    None,
    /// Cundall's non-viscous local damping: each component of the
    /// out-of-balance force (and the moment) is reduced by `α|F|`, against
    /// the velocity: `F ← F − α|F| sign(v)` (as in PFC and Yade).
    Local {
        /// Damping ratio α, 0 ≤ α < 1.
        alpha: f64,
    },
    /// Global mass damping of Eqs. (33)–(34): `m ü + c u̇ = F`,
    /// `I θ̈ + c* θ̇ = M`, integrated with the central difference.
    Mass {
        /// Translational coefficient `c` (force per velocity).
        c: f64,
        /// Rotational coefficient `c*` (moment per angular velocity).
        c_rot: f64,
    },
}

/// Kinetic, rotational and contact-spring energies.
#[derive(Debug, Clone, Copy, PartialEq, Default, serde::Serialize)]
pub struct Energies {
    /// Translational kinetic energy `Σ ½ m v²`.
    pub kinetic: f64,
    /// Rotational kinetic energy `Σ ½ I ω²`.
    pub rotational: f64,
    /// `½k_nδ² + F_s²/(2k_s)` (+ `M_r²/(2k_r)` with rolling resistance)
    /// over all contacts (disc–disc and disc–wall).
    pub spring: f64,
    /// `−Σ m g·x` (relative to the origin).
    pub gravity: f64,
    /// Strain energy of the intact parallel bonds ([`bonds::bond_energy`]).
    pub bond: f64,
}

impl Energies {
    /// The energies of the exact sums of
    /// [`Granular::energy_sums`] (kinetic, rotational, spring, gravity)
    /// and the bonds' energy.
    pub fn from_sums(s: &[ExactSum], bond: f64) -> Energies {
        Energies {
            kinetic: s[0].value(),
            rotational: s[1].value(),
            spring: s[2].value(),
            gravity: s[3].value(),
            bond,
        }
    }

    /// Kinetic + rotational + spring + gravity potential + bond energy.
    pub fn total(&self) -> f64 {
        self.kinetic + self.rotational + self.spring + self.gravity + self.bond
    }
}

/// A granular assembly: discs, walls, contact laws and contact state.
#[derive(Debug, Clone)]
pub struct Granular {
    /// The discs, in slots (see the module doc on slots vs ids).
    pub particles: Particles,
    /// The rigid walls, in scenario order.
    pub walls: Vec<Wall>,
    /// Per-material contact parameters (own values, dashpots from the damping).
    pub materials: Vec<ContactLaw>,
    /// Disc–disc laws, `laws[a * n_mat + b]` for materials a, b.
    pub laws: Vec<ContactLaw>,
    /// Disc–wall laws, `wall_laws[w * n_mat + a]`.
    pub wall_laws: Vec<ContactLaw>,
    /// [`ContactLaw::dashpot_terms`] of each entry of `laws`.
    dash: Vec<[f64; 4]>,
    /// Damping of the discs' motion (local or mass damping).
    pub damping: BodyDamping,
    /// Gravitational acceleration `g` acting on the discs.
    pub gravity: Vec2,
    /// Disc thickness t (discs are cylinders, default 1): stresses are
    /// forces per length × t (servo walls, [`measure`]).
    pub thickness: f64,
    /// Time step Δt of the central difference (ERRATA E11).
    pub dt: f64,
    /// Steps done.
    pub step: usize,
    /// Time reached.
    pub time: f64,
    /// Listed disc–disc and disc–wall pairs with their shear histories.
    pub contacts: ContactList,
    /// The contact search grid and its Verlet skin.
    pub grid: NeighbourGrid,
    /// Parallel bonds between discs ([`bonds`]; none unless a rule is set).
    pub bonds: Bonds,
    /// Rigid clumps of discs ([`clumps`]; none unless made).
    pub clumps: Clumps,
    /// Largest disc displacement since the last rebuild.
    pub max_disp: f64,
    /// Keep each disc's contact force and moment of the step in
    /// `particles.force`/`torque` (default). [`step`](Self::step) skips
    /// storing them when false, which saves a sixth of the memory traffic
    /// of a large run; `efgdem run` sets it only before the steps whose
    /// frames are written. The phased path always stores them.
    pub store_forces: bool,
    /// External forces of the next [`step`](Self::step): `(slot, force,
    /// moment)`, sorted by slot ([`set_external`](Self::set_external)).
    external: Vec<(u32, Vec2, f64)>,
    /// The disc check of [`step`](Self::step): radii per step a disc may
    /// move before it is flagged ([`step_check`](Self::step_check); the
    /// model sets its stability limit here).
    pub check_radii: f64,
    /// What the last [`step`](Self::step) found ([`step_check`](Self::step_check)).
    last_check: Option<StepCheck>,
    /// Each disc's position when the assembly was made (by id): the
    /// reference of [`displacement`](Self::displacement). Not part of the
    /// saved state: a restart rebuilds the assembly, which sets it again.
    start: Vec<Vec2>,
}

impl Granular {
    /// An assembly with the given discs, materials (dashpots already set in
    /// each law) and walls. The Verlet skin defaults to 0.1 × the largest
    /// radius.
    pub fn new(
        particles: Particles,
        materials: Vec<ContactLaw>,
        walls: Vec<Wall>,
        dt: f64,
    ) -> Granular {
        let mut particles = particles;
        particles.shrink_to_fit();
        let skin = 0.1 * particles.max_radius().max(f64::MIN_POSITIVE);
        // by id: a part of an assembly holds some of the whole's ids
        let ids = particles.id.iter().map(|&i| i as usize + 1).max();
        let mut start = vec![Vec2::ZERO; ids.unwrap_or(0).max(particles.len())];
        for (s, &id) in particles.id.iter().enumerate() {
            start[id as usize] = particles.pos[s];
        }
        let mut g = Granular {
            particles,
            walls,
            materials,
            laws: Vec::new(),
            wall_laws: Vec::new(),
            dash: Vec::new(),
            damping: BodyDamping::None,
            gravity: Vec2::ZERO,
            thickness: 1.0,
            dt,
            step: 0,
            time: 0.0,
            contacts: ContactList::default(),
            grid: NeighbourGrid::new(skin),
            bonds: Bonds::default(),
            clumps: Clumps::default(),
            max_disp: 0.0,
            store_forces: true,
            external: Vec::new(),
            check_radii: 1.0,
            last_check: None,
            start,
        };
        g.update_laws();
        g
    }

    /// Join the discs `ids` (scenario numbers, 0-based) into a rigid clump
    /// ([`Clumps::add`]); returns its index. The contact list is rebuilt
    /// at the next step (no pairs within a clump).
    pub fn add_clump(&mut self, ids: &[usize]) -> Result<usize, DemError> {
        let c = self
            .clumps
            .add(&mut self.particles, ids)
            .map_err(DemError::Input)?;
        self.grid.stale = true;
        Ok(c)
    }

    /// An assembly with the same materials, laws, walls, damping, clock,
    /// Verlet skin and rebuild count, holding `particles` instead (one part
    /// of a decomposed assembly): its contact list is built at its first
    /// step; it keeps no displacement reference
    /// ([`displacement`](Self::displacement) is not available).
    pub fn with_discs(&self, particles: Particles) -> Granular {
        Granular {
            particles,
            // bonded and clumped assemblies are not decomposed
            bonds: Bonds::default(),
            clumps: Default::default(),
            walls: self.walls.clone(),
            materials: self.materials.clone(),
            laws: self.laws.clone(),
            wall_laws: self.wall_laws.clone(),
            dash: self.dash.clone(),
            damping: self.damping,
            gravity: self.gravity,
            thickness: self.thickness,
            dt: self.dt,
            step: self.step,
            time: self.time,
            contacts: ContactList {
                rolling: self.contacts.rolling,
                needs_mass: self.contacts.needs_mass,
                ..Default::default()
            },
            grid: {
                let mut grid = NeighbourGrid::new(self.grid.skin);
                grid.reorder_every = self.grid.reorder_every;
                grid.rebuilds = self.grid.rebuilds;
                grid.wall_ref = self.grid.wall_ref.clone();
                grid
            },
            max_disp: self.max_disp,
            store_forces: self.store_forces,
            external: Vec::new(),
            check_radii: self.check_radii,
            last_check: None,
            start: Vec::new(),
        }
    }

    /// [`with_discs`](Self::with_discs) keeping the discs' start positions
    /// (by id, for [`displacement`](Self::displacement)): the assembly
    /// without its discs, or with the same discs gathered again.
    pub fn with_same_discs(&self, particles: Particles) -> Granular {
        let mut g = self.with_discs(particles);
        g.start.clone_from(&self.start);
        g
    }

    /// The start positions by id (for
    /// [`displacement`](Self::displacement)): a part of an assembly built
    /// alone takes its whole's.
    pub fn set_start(&mut self, by_id: Vec<Vec2>) {
        self.start = by_id;
    }

    /// Position of disc `id` when the assembly was made.
    pub fn start_position(&self, id: usize) -> Vec2 {
        self.start[id]
    }

    /// [`start_position`](Self::start_position), if the assembly holds it
    /// (a part of an assembly built alone holds it only where it serves).
    pub fn start_of(&self, id: usize) -> Option<Vec2> {
        self.start.get(id).copied()
    }

    /// Displacement of the disc in `slot` since the assembly was made (for a
    /// scenario: since t = 0, after any preparation).
    pub fn displacement(&self, slot: usize) -> Vec2 {
        let p = &self.particles;
        p.pos[slot] - self.start[p.id[slot] as usize]
    }

    /// Recompute the pair tables after changing `materials` or wall materials.
    pub fn update_laws(&mut self) {
        let nm = self.materials.len();
        self.laws = (0..nm * nm)
            .map(|k| ContactLaw::mix(&self.materials[k / nm], &self.materials[k % nm]))
            .collect();
        self.wall_laws = self
            .walls
            .iter()
            .flat_map(|w| {
                (0..nm).map(move |a| match w.material {
                    Some(m) => m as usize,
                    None => a,
                })
            })
            .map(|m| self.materials[m])
            .collect();
        self.dash = self.laws.iter().map(ContactLaw::dashpot_terms).collect();
        // rolling histories are kept only when some law needs them; the
        // list is rebuilt (histories from zero) when that changes
        let rolling = self.laws.iter().chain(&self.wall_laws).any(|l| l.rolling());
        if rolling != self.contacts.rolling {
            self.contacts.rolling = rolling;
            self.grid.stale = true;
        }
        // √m_eff is kept per pair only for critical-ratio dashpots
        let needs_mass = self.laws.iter().any(ContactLaw::needs_mass);
        if needs_mass != self.contacts.needs_mass {
            self.contacts.needs_mass = needs_mass;
            self.grid.stale = true;
        }
    }

    /// The Verlet skin (pairs with a gap below it are listed).
    pub fn set_skin(&mut self, skin: f64) {
        self.grid.skin = skin;
        self.grid.stale = true;
    }

    /// Largest contact stiffness of any law in use.
    pub fn k_max(&self) -> f64 {
        self.laws
            .iter()
            .chain(&self.wall_laws)
            .map(|l| l.kn.max(l.ks))
            .fold(0.0, f64::max)
    }

    /// A warning when Δt exceeds [`DT_WARN`] × the critical step
    /// ([`critical_step`](Self::critical_step), with the disc–body laws
    /// `bodies`).
    pub fn dt_warning(&self, bodies: &[ContactLaw]) -> Option<String> {
        let crit = self.critical_step(bodies);
        (self.dt > DT_WARN * crit.dt).then(|| {
            format!(
                "dt = {:e} is {:.3} × the critical step {:.4e} (of {}); above {DT_WARN} × it a dense packing, a packing of unequal discs or a contact whose overlap changes fast may not stay stable (a run that goes unstable stops with exit code 3); the default is {DT_SAFETY} ×",
                self.dt,
                self.dt / crit.dt,
                crit.dt,
                crit.mode
            )
        })
    }

    /// The critical step of the central difference for the contact laws
    /// in use ([`critical`]): the lightest disc's pair, wall and
    /// hexagonal-packing modes, dashpots included; `bodies` are the
    /// disc–body laws (a body taken as a rigid wall).
    pub fn critical_step(&self, bodies: &[ContactLaw]) -> critical::Critical {
        let p = &self.particles;
        let Some(k) = (0..p.len()).min_by(|&a, &b| p.mass[a].total_cmp(&p.mass[b])) else {
            return critical::Critical {
                dt: f64::INFINITY,
                mode: "no discs".into(),
                certain: f64::INFINITY,
            };
        };
        // a clump's rotation makes a contact at its rim lighter than a disc
        let d = critical::Disc {
            m: p.mass[k].min(self.clumps.min_effective_mass(p)),
            r: p.radius[k],
        };
        // the laws of the materials present
        let nm = self.materials.len();
        let mut present = vec![false; nm];
        for &m in &p.material {
            present[m as usize] = true;
        }
        let bond = self.bond_stiffness();
        let pairs: Vec<ContactLaw> = (0..nm * nm)
            .filter(|&ab| present[ab / nm] && present[ab % nm])
            .map(|ab| {
                let mut law = self.laws[ab];
                law.kn += bond.0;
                law.ks += bond.1;
                law
            })
            .collect();
        let walls: Vec<ContactLaw> = (0..self.walls.len() * nm)
            .filter(|&wa| present[wa % nm])
            .map(|wa| self.wall_laws[wa])
            .chain(bodies.iter().copied())
            .collect();
        critical::estimate(d, p.len(), &pairs, &walls)
    }

    /// The normal and shear stiffness a parallel bond adds to a pair in
    /// contact (zero without bonds): `k̄_n A` and `k̄_s A + k̄_n I / r²`
    /// (its bending taken as a shear spring at the disc's rim), with the
    /// section of the largest disc's bond — so that the pair and packing
    /// modes of [`critical_step`](Self::critical_step) bound bonded discs
    /// too.
    fn bond_stiffness(&self) -> (f64, f64) {
        if self.bonds.rule.is_none() {
            return (0.0, 0.0);
        }
        let law = &self.bonds.law;
        let r = self.particles.radius.iter().copied().fold(0.0, f64::max);
        let (a, i) = bonds::section(law.radius_factor * r, self.thickness);
        (law.kn * a, law.ks * a + law.kn * i / (r * r))
    }

    /// `2√(m_min/k_max)`: the critical step of the lightest disc on a wall
    /// of the stiffest law, undamped — not a bound for a pair or a packing
    /// ([`critical_step`](Self::critical_step)); the packing preparations
    /// use a fraction of it.
    /// With parallel bonds, at most that of each bonded disc against its
    /// bond's stiffness ([`Bonds::critical_dt`]).
    pub fn critical_dt(&self) -> f64 {
        let k = self.k_max();
        let m = (self.particles.min_mass()).min(self.clumps.min_effective_mass(&self.particles));
        let contacts = if k > 0.0 && m.is_finite() {
            2.0 * (m / k).sqrt()
        } else {
            f64::INFINITY
        };
        contacts.min(
            self.bonds
                .critical_dt(&self.particles, self.thickness, self.k_max()),
        )
    }

    /// One full time step: the three phases in order, with the external
    /// forces of [`set_external`](Self::set_external) if any, fused into one [`sweep`] over the discs (each disc advances
    /// as soon as its contacts are summed); bitwise the same result as
    /// calling [`prepare_contacts`](Self::prepare_contacts),
    /// [`compute_contact_forces`](Self::compute_contact_forces) and
    /// [`integrate`](Self::integrate).
    pub fn step(&mut self) {
        let bad = self.advance_discs();
        self.wall_totals();
        self.finish_step(!bad);
    }

    /// The discs' part of [`step`](Self::step): the contact list prepared,
    /// every contact evaluated and every disc advanced in one sweep
    /// (`max_disp` set), every clump advanced under its members' forces
    /// and its members placed: in the sweep, after the block that holds
    /// its members, or after the sweep when they lie in more than one
    /// block ([`Clumps::step_across`]). Returns whether some disc failed
    /// the step check ([`step_check`](Self::step_check)).
    /// The walls' totals and motion follow: [`wall_totals`](Self::wall_totals)
    /// (or [`set_wall_totals`](Self::set_wall_totals)), then
    /// [`finish_step`](Self::finish_step).
    pub fn advance_discs(&mut self) -> bool {
        self.prepare_contacts();
        let (mut max_disp, mut bad) = self.sweep::<true>();
        if !self.clumps.is_empty() {
            let max_v2 = self.check_v2();
            let (d2, b) = self.clumps.step_across(
                &mut self.particles,
                &self.grid.ref_pos,
                (self.gravity, self.damping, self.dt),
                max_v2,
            );
            // √ is monotone and correctly rounded: the largest of the two
            // roots is the root of the largest square
            max_disp = max_disp.max(d2.sqrt());
            bad |= b;
        }
        self.max_disp = max_disp;
        self.external.clear();
        bad
    }

    /// Hold the discs in `slots` out of the next
    /// [`advance_discs`](Self::advance_discs): their contacts are summed
    /// as usual but they are not advanced (the discs' neighbours read them
    /// unmoved, as they would anyway); [`release_held`](Self::release_held)
    /// advances them once forces computed beside the sweep are set. Not
    /// for clumped assemblies (a clump sums its members in the sweep).
    pub fn hold(&mut self, slots: &[u32]) {
        assert!(self.clumps.is_empty(), "held discs in a clumped assembly");
        for &s in slots {
            self.particles.fixity[s as usize] |= particles::HELD;
        }
    }

    /// Advance the discs held by [`hold`](Self::hold) (`slots`, ascending),
    /// after [`advance_discs`](Self::advance_discs) and
    /// [`set_external`](Self::set_external): each with the sums the sweep
    /// left in `force`/`torque`, then its external forces in order — the
    /// sweep's sums, so bitwise the step it would have taken there.
    /// `max_disp` takes their displacements; returns whether one failed
    /// the step check.
    pub fn release_held(&mut self, slots: &[u32]) -> bool {
        let max_v2 = self.check_v2();
        let (g, damping, dt) = (self.gravity, self.damping, self.dt);
        let p = &mut self.particles;
        let ref_pos = &self.grid.ref_pos;
        let has_ref = ref_pos.len() == p.len();
        let ext = &self.external;
        let (mut ek, mut m2, mut bad) = (0, 0.0f64, false);
        for &s in slots {
            let d = s as usize;
            p.fixity[d] &= !particles::HELD;
            let (mut sf, mut tq) = (p.force[d], p.torque[d]);
            sweep::add_external(ext, &mut ek, d, &mut sf, &mut tq);
            (p.force[d], p.torque[d]) = (sf, tq);
            if p.fixity[d] & particles::GHOST != 0 {
                continue;
            }
            let (x, v, th, w) = (
                &mut p.pos[d],
                &mut p.vel[d],
                &mut p.theta[d],
                &mut p.omega[d],
            );
            let (im, ii, fix) = (p.inv_mass[d], p.inv_inertia[d], p.fixity[d]);
            integrate::advance(x, v, th, w, sf, tq, im, ii, fix, g, damping, dt);
            if has_ref {
                m2 = m2.max((*x - ref_pos[d]).norm2());
            }
            bad |= !integrate::passes_check(*x, *v, *w, p.radius[d], max_v2);
        }
        assert_eq!(ek, ext.len(), "an external force on a disc not held");
        self.external.clear();
        if has_ref {
            self.max_disp = self.max_disp.max(m2.sqrt());
        }
        bad
    }

    /// `(check_radii/Δt)²`, the speed bound of the per-step check
    /// ([`integrate::passes_check`]).
    pub(super) fn check_v2(&self) -> f64 {
        self.check_radii * self.check_radii / (self.dt * self.dt)
    }

    /// The end of [`step`](Self::step): the walls move, the clock
    /// advances, and the step check is recorded (`clean`: every disc
    /// passed it).
    pub fn finish_step(&mut self, clean: bool) {
        self.move_walls();
        self.last_check = Some(StepCheck {
            step: self.step,
            radii_per_step: self.check_radii,
            clean,
        });
    }

    /// Did the last [`step`](Self::step), which brought the assembly to
    /// its present step, find every disc finite and moving at most
    /// `radii_per_step` radii per step (`v·v ≤ (radii_per_step/Δt)² r²`)?
    /// `None` when the present state was not made by `step` with that
    /// bound (then check the discs themselves).
    pub fn step_check(&self, radii_per_step: f64) -> Option<bool> {
        self.last_check
            .filter(|c| c.step == self.step && c.radii_per_step == radii_per_step)
            .map(|c| c.clean)
    }

    /// External forces for the next [`step`](Self::step) (e.g. the
    /// disc–body contacts of the coupling): `f` acting at `point` on the
    /// disc in `slot`, i.e. the force plus the moment `(point − x) × f`
    /// (ERRATA E12), summed after the disc's contacts in the order given
    /// (the same sums as [`add_external_force`](Self::add_external_force)
    /// on the phased path). Call after
    /// [`prepare_contacts`](Self::prepare_contacts), which may renumber the
    /// slots; cleared by the step.
    pub fn set_external(&mut self, forces: impl IntoIterator<Item = (usize, Vec2, Vec2)>) {
        self.set_external_with_moments(forces.into_iter().map(|(s, f, x)| (s, f, x, 0.0)));
    }

    /// [`set_external`](Self::set_external) with a pure moment `m` added
    /// to each force's moment (e.g. the rolling resistance of a disc–body
    /// contact; `m = 0` adds nothing, bitwise).
    pub fn set_external_with_moments(
        &mut self,
        forces: impl IntoIterator<Item = (usize, Vec2, Vec2, f64)>,
    ) {
        let p = &self.particles;
        self.external.clear();
        self.external
            .extend(forces.into_iter().map(|(slot, f, point, m)| {
                let mut moment = (point - p.pos[slot]).cross(f);
                if m != 0.0 {
                    moment += m;
                }
                (slot as u32, f, moment)
            }));
        // stable: several forces on one disc keep their order
        self.external.sort_by_key(|e| e.0);
    }

    /// Phase 1: rebuild the neighbour list when the Verlet criterion says
    /// so (or it was never built); bond the discs when the bond rule's step
    /// has come ([`bonds::BondRule`]).
    pub fn prepare_contacts(&mut self) {
        if self.grid.needs_rebuild(self.max_disp, &self.walls) {
            self.rebuild();
        }
        if let Some(rule) = &self.bonds.rule
            && !self.bonds.list.created
            && self.step >= rule.at_step
        {
            self.make_bonds();
        }
    }

    /// Rebuild the neighbour list now (the discs may be renumbered).
    fn rebuild(&mut self) {
        self.grid
            .rebuild(&mut self.particles, &self.walls, &mut self.contacts);
        self.max_disp = 0.0;
        self.bonds.invalidate();
        self.clumps.invalidate();
    }

    /// Apply the bond rule to the present state: every listed pair whose
    /// gap is below the rule's (the list is rebuilt first with a skin that
    /// reaches that gap, if the present one does not).
    fn make_bonds(&mut self) {
        let Some(rule) = &self.bonds.rule else { return };
        let reach = rule.gap * self.particles.max_radius();
        let skin = self.grid.skin;
        if reach >= skin {
            self.grid.skin = reach * 1.01;
            self.rebuild();
            self.grid.skin = skin;
            self.grid.stale = true;
        } else if self.contacts.first.len() != self.particles.len() + 1 {
            self.rebuild();
        }
        self.bonds.create(&self.particles, self.contacts.pairs());
    }

    /// Phase 2: evaluate every listed contact and *overwrite* each disc's
    /// force and torque with the sum of its contacts, in a fixed order
    /// (bitwise independent of the thread count, see [`sweep`]). Also sets
    /// each wall's force.
    /// It also advances the parallel bonds by one step: call it once per
    /// step.
    pub fn compute_contact_forces(&mut self) {
        self.sweep::<false>();
        self.wall_totals();
    }

    /// Total force on each wall: minus the sum of its contact forces, in
    /// the fixed order of the wall-pair list; for servo and strain-rate
    /// walls also the number of discs touching it, their `Σ k_n` and
    /// `Σ c_n` (the servo's stiffness and damping).
    pub fn wall_totals(&mut self) {
        let terms: Vec<WallTerm> = self.wall_terms().collect();
        self.set_wall_totals(&terms);
    }

    /// What each disc–wall pair of the present step adds to its wall's
    /// totals, in list order (by disc slot, then wall).
    pub fn wall_terms(&self) -> impl Iterator<Item = WallTerm> + '_ {
        let nm = self.materials.len();
        let p = &self.particles;
        self.contacts
            .walls
            .iter()
            .zip(&self.contacts.wall_buf)
            .map(move |(q, cf)| {
                let (wi, d) = (q.wall as usize, q.disc as usize);
                let counted = cf.f != Vec2::ZERO && self.walls[wi].motion.follows_state();
                let (kn, cn) = if counted {
                    let law = &self.wall_laws[wi * nm + p.material[d] as usize];
                    (law.kn, law.dashpots(effective_mass(p.inv_mass[d], 0.0)).0)
                } else {
                    (0.0, 0.0)
                };
                WallTerm {
                    disc: q.disc,
                    wall: q.wall,
                    f: cf.f,
                    counted,
                    kn,
                    cn,
                }
            })
    }

    /// Set each wall's totals from `terms` `(wall, term)`, summed in the
    /// order given ([`wall_totals`](Self::wall_totals) gives them in list
    /// order; the parts of a decomposed assembly merge theirs into the
    /// same order).
    pub fn set_wall_totals<'a>(&mut self, terms: impl IntoIterator<Item = &'a WallTerm>) {
        for w in &mut self.walls {
            w.force = Vec2::ZERO;
            w.contacts = 0;
            w.stiffness = 0.0;
            w.damping = 0.0;
        }
        for t in terms {
            let w = &mut self.walls[t.wall as usize];
            w.force -= t.f;
            if t.counted {
                w.contacts += 1;
                w.stiffness += t.kn;
                w.damping += t.cn;
            }
        }
    }

    /// Add an external force `f` acting at `point` on the disc in `slot`
    /// (e.g. a disc–body-boundary contact of the coupling): force plus the
    /// moment `(point − x) × f` (ERRATA E12). Call between
    /// [`compute_contact_forces`](Self::compute_contact_forces) and
    /// [`integrate`](Self::integrate).
    pub fn add_external_force(&mut self, slot: usize, f: Vec2, point: Vec2) {
        let p = &mut self.particles;
        p.force[slot] += f;
        p.torque[slot] += (point - p.pos[slot]).cross(f);
    }

    /// Add a pure moment to the disc in `slot` (e.g. the rolling
    /// resistance of a disc–body contact), between the same phases as
    /// [`add_external_force`](Self::add_external_force).
    pub fn add_external_moment(&mut self, slot: usize, m: f64) {
        self.particles.torque[slot] += m;
    }

    /// Phase 3: gravity, damping, central difference (Eqs. 50–54, E10),
    /// then the walls move and the clock advances.
    pub fn integrate(&mut self) {
        self.clumps.gather(&self.particles);
        let d = integrate::central_difference(
            &mut self.particles,
            &self.grid.ref_pos,
            self.gravity,
            self.damping,
            self.dt,
        );
        self.max_disp = if self.clumps.is_empty() {
            d
        } else {
            self.clumps
                .advance(&mut self.particles, self.gravity, self.damping, self.dt);
            self.largest_displacement()
        };
        self.move_walls();
    }

    /// Largest disc displacement since the last rebuild (infinity without
    /// a reference).
    fn largest_displacement(&self) -> f64 {
        let r = &self.grid.ref_pos;
        let p = &self.particles.pos;
        if r.len() != p.len() {
            return f64::INFINITY;
        }
        p.iter()
            .zip(r)
            .map(|(&a, &b)| (a - b).norm2())
            .fold(0.0, f64::max)
            .sqrt()
    }

    /// Walls move: every velocity is found from the state before any wall
    /// moves ([`wall_velocity`](Self::wall_velocity)), then each wall
    /// translates by `v Δt` and its joined ends are put back on the lines
    /// of the walls they follow. The clock advances.
    fn move_walls(&mut self) {
        for k in 0..self.walls.len() {
            let (v, integral) = self.wall_motion(k);
            self.walls[k].vel = v;
            self.walls[k].integral = integral;
        }
        let mut joined = false;
        for w in &mut self.walls {
            w.translate(w.vel * self.dt);
            joined |= w.is_joined();
        }
        if joined {
            self.join_walls();
        }
        self.step += 1;
        self.time = self.step as f64 * self.dt;
    }

    /// Velocity of wall `k` during the present step (the motion of its
    /// phase at this step, [`walls::WallMotion::at`]): the prescribed one,
    /// the servo's `−inward · G (F − σ L t)` from the force of the step
    /// just computed ([`walls::Servo`]), or the strain rate's
    /// `inward · share ε̇ D` from the present distance D to the opposite
    /// wall.
    pub fn wall_velocity(&self, k: usize) -> Vec2 {
        self.wall_motion(k).0
    }

    /// [`wall_velocity`](Self::wall_velocity) and the servo's integral
    /// velocity for the next step ([`walls::Servo::speed_integral`]; 0
    /// when the wall is not a servo at this step).
    fn wall_motion(&self, k: usize) -> (Vec2, f64) {
        let w = &self.walls[k];
        let v = match w.motion.at(self.step) {
            walls::WallMotion::Servo(s) => {
                let target = s.stress * w.length() * self.thickness;
                let stiffness = if w.contacts > 0 {
                    w.stiffness
                } else {
                    self.wall_kn_max(k)
                };
                let (v, integral) = s.speed_integral(
                    w.normal_force(),
                    target,
                    stiffness,
                    w.damping,
                    self.dt,
                    w.integral,
                );
                return (w.inward * -v, integral);
            }
            walls::WallMotion::StrainRate {
                rate,
                opposite,
                share,
            } => {
                let d = (self.walls[*opposite].a - w.a).dot(w.inward);
                w.inward * (share * rate * d)
            }
            m => m.velocity(self.step, self.time, self.dt),
        };
        (v, 0.0)
    }

    /// Largest normal stiffness of wall `k` against any disc material.
    fn wall_kn_max(&self, k: usize) -> f64 {
        let nm = self.materials.len();
        self.wall_laws[k * nm..(k + 1) * nm]
            .iter()
            .map(|l| l.kn)
            .fold(0.0, f64::max)
    }

    /// Put every joined end on the line of the wall it follows (the line
    /// of this wall through `a` along its fixed direction: the wall
    /// stretches or shrinks, it does not turn).
    fn join_walls(&mut self) {
        for k in 0..self.walls.len() {
            let w = &self.walls[k];
            let ends = w
                .joins
                .map(|j| j.and_then(|j| w.meet(&self.walls[j as usize])));
            let w = &mut self.walls[k];
            if let Some(a) = ends[0] {
                w.a = a;
            }
            if let Some(b) = ends[1] {
                w.b = b;
            }
        }
    }

    /// Is every disc state, and every wall's position, finite?
    pub fn is_finite(&self) -> bool {
        let p = &self.particles;
        p.pos
            .iter()
            .chain(&p.vel)
            .chain(self.walls.iter().flat_map(|w| [&w.a, &w.b]))
            .all(|v| v.x.is_finite() && v.y.is_finite())
            && p.omega.iter().all(|w| w.is_finite())
            && self.clumps.is_finite()
    }

    /// [`DemError::Unstable`] at the present step unless every disc state
    /// is finite.
    pub fn check_finite(&self) -> Result<(), DemError> {
        // a clean check of the step that made this state covers it
        if self.step_check(self.check_radii) == Some(true) || self.is_finite() {
            Ok(())
        } else {
            Err(DemError::Unstable {
                step: self.step,
                dt_crit: self.critical_step(&[]).dt,
            })
        }
    }

    /// Slot of scenario disc `id` (0-based).
    pub fn slot(&self, id: usize) -> usize {
        self.particles.slot[id] as usize
    }

    /// The law between the discs in slots `a` and `b`.
    pub fn law(&self, a: usize, b: usize) -> &ContactLaw {
        let p = &self.particles;
        &self.laws[p.material[a] as usize * self.materials.len() + p.material[b] as usize]
    }

    /// Normal force between the discs in slots `a` and `b` from the present
    /// positions and velocities: (elastic `k_n δ`, total with the dashpot).
    pub fn normal_force(&self, a: usize, b: usize) -> (f64, f64) {
        let p = &self.particles;
        let (n, dist) = normal_between(p.pos[a], p.pos[b]);
        let delta = p.radius[a] + p.radius[b] - dist;
        let vn = (p.vel[a] - p.vel[b]).dot(n);
        let m_eff = effective_mass(p.inv_mass[a], p.inv_mass[b]);
        contact::normal_force(self.law(a, b), delta, vn, m_eff)
    }

    /// The disc–wall contact `q` of the present state, if closed: the
    /// contact point on the wall, the unit normal from the disc towards
    /// it, the overlap and the normal force (elastic `k_n δ`, total with
    /// the dashpot), as for [`normal_force`](Self::normal_force).
    pub fn wall_contact(&self, q: &broadphase::WallPair) -> Option<WallContact> {
        let p = &self.particles;
        let (d, w) = (q.disc as usize, q.wall as usize);
        let wall = &self.walls[w];
        let point = wall.closest(p.pos[d]);
        let dist = (point - p.pos[d]).norm();
        let overlap = p.radius[d] - dist;
        if overlap <= 0.0 || dist == 0.0 {
            return None;
        }
        let normal = (point - p.pos[d]) * (1.0 / dist);
        let law = &self.wall_laws[w * self.materials.len() + p.material[d] as usize];
        let vn = (p.vel[d] - wall.vel).dot(normal);
        let (elastic, total) =
            contact::normal_force(law, overlap, vn, effective_mass(p.inv_mass[d], 0.0));
        Some(WallContact {
            point,
            normal,
            overlap,
            elastic,
            total,
        })
    }

    /// Energies from the present positions, the given velocities and spins,
    /// and the present shear histories. With the central difference the
    /// state after a step has positions at t + Δt and velocities at
    /// t + Δt/2; pass synchronous velocities for an exact energy balance.
    pub fn energies_with(&self, vel: &[Vec2], omega: &[f64]) -> Energies {
        Energies::from_sums(
            &self.energy_sums(vel, omega),
            self.bonds.energy(self.thickness),
        )
    }

    /// The exact sums behind [`energies_with`](Self::energies_with)
    /// (kinetic, rotational, spring, gravity) over the discs that are not
    /// ghosts and the pairs whose first disc is not one: the terms of a
    /// part of a divided assembly, whose sums over the parts are exactly
    /// those of the whole.
    pub fn energy_sums(&self, vel: &[Vec2], omega: &[f64]) -> [ExactSum; 4] {
        let p = &self.particles;
        let mut e: [ExactSum; 4] = Default::default();
        let own = |k: usize| !p.is_ghost(k);
        for k in (0..p.len()).filter(|&k| own(k)) {
            if p.clump[k] != clumps::NO_CLUMP {
                continue; // counted with its clump below
            }
            e[0].add(0.5 * p.mass[k] * vel[k].norm2());
            e[1].add(0.5 * p.inertia[k] * omega[k] * omega[k]);
            e[3].add(-(p.mass[k] * self.gravity.dot(p.pos[k])));
        }
        let c = &self.clumps;
        for k in 0..c.len() {
            e[0].add(0.5 * c.mass[k] * c.vel[k].norm2());
            e[1].add(0.5 * c.inertia[k] * c.omega[k] * c.omega[k]);
            e[3].add(-(c.mass[k] * self.gravity.dot(c.pos[k])));
        }
        let spring = |law: &ContactLaw, delta: f64, fs: f64| {
            if delta <= 0.0 {
                return 0.0;
            }
            let mut s = 0.5 * law.kn * delta * delta;
            if law.ks > 0.0 {
                s += 0.5 * fs * fs / law.ks;
            }
            s
        };
        let roll = &self.contacts.roll;
        let rolling = self.contacts.rolling && roll.len() == self.contacts.len();
        for (k, ((i, j), &fs)) in self.contacts.pairs().zip(&self.contacts.shear).enumerate() {
            if !own(i) {
                continue;
            }
            let dist = (p.pos[j] - p.pos[i]).norm();
            let (ri, rj) = (p.radius[i], p.radius[j]);
            let law = self.law(i, j);
            e[2].add(spring(law, ri + rj - dist, fs));
            if rolling && ri + rj > dist {
                e[2].add(contact::rolling_energy(
                    law,
                    contact::rolling_radius(ri, rj),
                    roll[k],
                ));
            }
        }
        let nm = self.materials.len();
        for q in self.contacts.walls.iter().filter(|q| own(q.disc as usize)) {
            let d = q.disc as usize;
            let w = &self.walls[q.wall as usize];
            let dist = (w.closest(p.pos[d]) - p.pos[d]).norm();
            let law = &self.wall_laws[q.wall as usize * nm + p.material[d] as usize];
            e[2].add(spring(law, p.radius[d] - dist, q.fs));
            if q.mr != 0.0 && p.radius[d] > dist {
                e[2].add(contact::rolling_energy(law, p.radius[d], q.mr));
            }
        }
        e
    }

    /// Energies of the present state (velocities at the half step).
    pub fn energies(&self) -> Energies {
        self.energies_with(&self.particles.vel, &self.particles.omega)
    }

    /// Number of listed pairs that are touching (disc–disc, disc–wall);
    /// of a part of a divided assembly, those whose first disc is not a
    /// ghost (see [`energy_sums`](Self::energy_sums)).
    pub fn touching(&self) -> (usize, usize) {
        let p = &self.particles;
        let own = |k: usize| !p.is_ghost(k);
        let dd = self
            .contacts
            .pairs()
            .filter(|&(i, j)| {
                let r = p.radius[i] + p.radius[j];
                own(i) && (p.pos[j] - p.pos[i]).norm2() < r * r
            })
            .count();
        let dw = self
            .contacts
            .walls
            .iter()
            .filter(|q| {
                let d = q.disc as usize;
                if !own(d) {
                    return false;
                }
                let w = &self.walls[q.wall as usize];
                (w.closest(p.pos[d]) - p.pos[d]).norm2() < p.radius[d] * p.radius[d]
            })
            .count();
        (dd, dw)
    }

    /// Heap bytes held by the assembly (discs + contact list + grid +
    /// bonds).
    pub fn heap_bytes(&self) -> usize {
        self.particles.heap_bytes()
            + self.contacts.heap_bytes()
            + self.grid.heap_bytes()
            + self.bonds.heap_bytes()
            + self.clumps.heap_bytes()
    }
}
