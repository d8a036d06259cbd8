//! Crack growth of an EFG body: at each tip the stress intensity factors
//! ([`super::fracture`]) give the maximum hoop-stress direction `θ_c` and
//! the equivalent `K_eq` ([`max_hoop_stress`]); a tip with `K_eq ≥ K_Ic`
//! advances by Δa along `θ_c`, and the body is built again with the longer
//! crack — its node set follows the crack (the refined band along the
//! crack, the face nodes of the new piece) — with its state carried over.
//!
//! **The increment.** By default Δa is the outer radius of the tip's
//! interaction-integral ring (5 tip spacings): the next ring then sees a
//! straight crack (its kink lies at the ring's edge), the new piece spans
//! several face-node pairs, and the path is resolved at the scale of the
//! refined band. A smaller Δa puts the kink inside the next ring (whose
//! integral assumes straight faces); a larger one follows a curving path
//! more coarsely.
//!
//! **The state.** The displacement, velocity and acceleration fields of the
//! old body are carried to the new one by `L²` projection, `G Û = ∫ Φᵀ u
//! t dΩ` on the new body's integration points (`G` its Gram matrix): the
//! field is kept in the mean over the body rather than at the nodes (EFG
//! parameters are not nodal values). The clock, the drives and the work
//! counters are the old body's.
//!
//! **The energy.** Each growth books `G Δa t` (`G = (K_I² + K_II²)/E′`,
//! Irwin) in [`EfgBody::fracture_energy`]: the energy the crack takes to
//! advance, which the energy account counts as dissipated by fracture.

use super::EfgError;
use super::body::EfgBody;
use super::fracture::Tip;
use super::penalty::When;
use super::shape::ShapeRow;
use crate::continuum::Plane;
use crate::continuum::crack_tip::{e_prime, energy_release_rate, max_hoop_stress};
use crate::geom::Vec2;
use crate::geom::polygon::segments_meet;
use crate::sparse::Cholesky;
use rayon::prelude::*;

/// A point's new shape row and the old fields there.
type Projected = (ShapeRow, [[f64; 2]; 3]);

/// One advance of one tip.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Growth {
    /// The tip.
    pub tip: Tip,
    /// Where it was.
    pub from: Vec2,
    /// Where it is now.
    pub to: Vec2,
    /// `[K_I, K_II]` before the advance.
    pub k: [f64; 2],
    /// The kink angle `θ_c` (radians, from the old direction, positive to
    /// the left).
    pub theta: f64,
    /// `K_eq` of the maximum hoop-stress criterion.
    pub k_eq: f64,
    /// Energy released, `G Δa t`.
    pub released: f64,
}

/// A tip's state against the criterion, without growing it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TipState {
    /// The tip.
    pub tip: Tip,
    /// `[K_I, K_II]`.
    pub k: [f64; 2],
    /// `θ_c` (radians).
    pub theta: f64,
    /// `K_eq`.
    pub k_eq: f64,
}

impl EfgBody {
    /// `K`, `θ_c` and `K_eq` at every tip (default rings).
    pub fn tip_states(&self) -> Result<Vec<TipState>, EfgError> {
        self.tips()
            .into_iter()
            .map(|tip| {
                let k = self.stress_intensity(tip, self.default_ring(tip))?;
                let (theta, k_eq) = max_hoop_stress(k);
                Ok(TipState {
                    tip,
                    k,
                    theta,
                    k_eq,
                })
            })
            .collect()
    }

    /// Grow every tip that meets the criterion of the body's
    /// [`Fracture`](crate::continuum::Fracture) by one increment (module
    /// doc), rebuild the body and carry its state over. A tip whose new
    /// piece would come closer than Δa/2 to the boundary or meet another
    /// crack stays (growth to the boundary would split the body). Returns
    /// the advances (none: the body is unchanged).
    pub fn grow(&mut self) -> Result<Vec<Growth>, EfgError> {
        self.grow_under(&[])
    }

    /// [`grow`](Self::grow) for a body that also carries the point forces
    /// `loads` (`(reference point, force)`, e.g. the discs' contact forces
    /// of the present state): they hold the body while its new pieces
    /// open ([`release`](Self::release)).
    pub fn grow_under(&mut self, loads: &[(Vec2, Vec2)]) -> Result<Vec<Growth>, EfgError> {
        let Some(fr) = self.spec.fracture else {
            return Ok(Vec::new());
        };
        let states = self.tip_states()?;
        let mut spec = self.spec.clone();
        let mut out = Vec::new();
        let t = self.material.thickness;
        let m = &self.material;
        let ep = e_prime(m.e, m.nu, m.plane == Plane::Strain);
        for s in states {
            let Tip { crack, end } = s.tip;
            if s.k_eq < fr.toughness || self.increments[crack][end] >= fr.max_increments {
                continue;
            }
            let (from, dir) = self.tip_frame(s.tip);
            let da = fr
                .increment
                .unwrap_or_else(|| self.default_ring(s.tip).outer);
            let (sn, cs) = s.theta.sin_cos();
            let to = from + (dir * cs + dir.perp() * sn) * da;
            if !self.room_for(crack, from, to, 0.5 * da) {
                continue;
            }
            let pts = &mut spec.cracks[crack].crack.points;
            if end == 0 {
                pts.insert(0, to);
            } else {
                pts.push(to);
            }
            out.push(Growth {
                tip: s.tip,
                from,
                to,
                k: s.k,
                theta: s.theta,
                k_eq: s.k_eq,
                released: energy_release_rate(s.k, ep) * da * t,
            });
        }
        if out.is_empty() {
            return Ok(out);
        }
        let mut new = EfgBody::new(&spec, self.gravity)?;
        new.take_state_of(self)?;
        new.increments.clone_from(&self.increments);
        for g in &out {
            new.increments[g.tip.crack][g.tip.end] += 1;
        }
        let mut row = ShapeRow::new();
        for &(p, f) in loads {
            // as the coupling's rows: a point no node covers carries nothing
            if new.shape_row(p, &mut row).is_ok() {
                new.add_point_load_row(&row, f);
            }
        }
        let held = new.release()?;
        new.fracture_energy =
            self.fracture_energy + self.energy_less_work() - new.energy_less_work() + held;
        *self = new;
        Ok(out)
    }

    /// A static analysis with growth: solve, then as long as a tip meets
    /// the criterion grow it and solve again under the same loads (each
    /// tip at most `max_increments` times). Returns every advance.
    pub fn solve_static_growing(&mut self) -> Result<Vec<Growth>, EfgError> {
        self.solve_static()?;
        let mut all = Vec::new();
        loop {
            let g = self.grow()?;
            if g.is_empty() {
                return Ok(all);
            }
            all.extend(g);
            self.solve_static()?;
        }
    }

    /// In a time-stepped run: [`grow_under`](Self::grow_under) when the
    /// step count is a multiple of the fracture's `every`.
    pub fn grow_if_due(&mut self, loads: &[(Vec2, Vec2)]) -> Result<Vec<Growth>, EfgError> {
        match self.spec.fracture {
            Some(f) if self.step.is_multiple_of(f.every.max(1)) => self.grow_under(loads),
            _ => Ok(Vec::new()),
        }
    }

    /// Stored energy less the work of the body's own loads:
    /// `½U̇ᵀMU̇ + ½UᵀKU` + the penalty springs and crack faces − the work
    /// of the permanent (and, static, released) loads, the timed loads and
    /// the moving edges.
    fn energy_less_work(&self) -> f64 {
        let mut f = self.f_permanent.clone();
        if self.newmark().is_none() {
            f.iter_mut()
                .zip(&self.f_released)
                .for_each(|(a, b)| *a += b);
        }
        let fu: f64 = f.iter().zip(&self.state.u).map(|(f, u)| f * u).sum();
        self.kinetic_energy() + self.strain_energy() - fu - self.load_work - self.motion_work
    }

    /// Let a body just carried over from a body with shorter cracks open
    /// its new pieces (module doc, *the energy*): the carried state is
    /// continuous across them, so it is out of balance by the tractions
    /// the cut removed, `r = F − K̄U − MÜ − CU̇` (`F` the body's loads at the
    /// present time, with the pending point loads); the body relaxes by
    /// `ΔU = K̄⁻¹ r`, its velocity and acceleration kept, and is in balance
    /// again. The timed loads' work on `ΔU` is booked with them; the point
    /// loads are then cleared and their work on `ΔU` returned.
    fn release(&mut self) -> Result<f64, EfgError> {
        let n = self.n_dofs();
        let mut r = self.f_point.clone();
        let mut timed = vec![0.0; n];
        for l in &self.timed {
            l.add_to(&mut timed, self.time);
        }
        let mut ku = vec![0.0; n];
        let kbar = self.ops.kbar();
        kbar.mul_add(&self.state.u, &mut ku);
        if let Some(nm) = self.newmark() {
            nm.mass.mul_add(&self.state.a, &mut ku);
            if let Some(c) = &nm.damping {
                c.mul_add(&self.state.v, &mut ku);
            }
        } else {
            r.iter_mut()
                .zip(&self.f_released)
                .for_each(|(a, b)| *a += b);
        }
        self.ops.penalty.add_load(&mut r, When::Now);
        for i in 0..n {
            r[i] += self.f_permanent[i] + timed[i] - ku[i];
        }
        Cholesky::factor(&kbar)?.solve_in_place(&mut r);
        let dot = |a: &[f64]| a.iter().zip(&r).map(|(x, y)| x * y).sum::<f64>();
        self.load_work += dot(&timed);
        let held = dot(&self.f_point);
        for (u, d) in self.state.u.iter_mut().zip(&r) {
            *u += d;
        }
        self.f_point.iter_mut().for_each(|x| *x = 0.0);
        Ok(held)
    }

    /// How many times the body was rebuilt by growth (0: as built from
    /// the scenario): shape rows bound earlier belong to that generation.
    pub fn generation(&self) -> usize {
        self.increments.iter().map(|i| i[0] + i[1]).sum()
    }

    /// May crack `crack` run on from `from` to `to`: `to` inside the body
    /// and at least `clear` from its boundary, the new piece meeting no
    /// other crack?
    fn room_for(&self, crack: usize, from: Vec2, to: Vec2, clear: f64) -> bool {
        let Some(mesh) = &self.mesh else {
            return false;
        };
        if !mesh.domain.contains(to) || mesh.domain.boundary_distance(to) < clear {
            return false;
        }
        let own = &self.cracks()[crack].crack;
        self.cracks().iter().enumerate().all(|(k, c)| {
            let cr = &c.crack;
            (0..cr.pieces()).all(|i| {
                let (a, b) = cr.piece(i);
                // the tip's own piece meets the new one at the tip
                let adjacent = k == crack && (a == from || b == from);
                adjacent || !segments_meet(a, b, from, to)
            }) && (k == crack || cr.distance(to) >= clear)
        }) && own
            .points
            .iter()
            .all(|&p| p == from || (p - to).norm() >= clear)
    }

    /// Take over the evolving state of `old` (a body of the same scenario
    /// with shorter cracks): `U`, `U̇`, `Ü` by `L²` projection (module
    /// doc), the clock, drives and work counters as they are; the
    /// integrator restarted if `old`'s was.
    pub fn take_state_of(&mut self, old: &EfgBody) -> Result<(), EfgError> {
        let fields = self.project(old, [&old.state.u, &old.state.v, &old.state.a])?;
        let mut s = old.save_state();
        let [u, v, a] = fields;
        s.state.u = u;
        s.state.v = v;
        s.state.a = a;
        s.f_point = vec![0.0; self.n_dofs()];
        s.cracks = None; // the cracks are this body's
        if old.newmark().is_some() {
            self.start_dynamic(old.params.dt)?;
        }
        self.restore_state(&s)
            .map_err(|e| EfgError::Invalid(e.to_string()))?;
        Ok(())
    }

    /// `L²` projection of fields of `old` onto this body's shape functions.
    fn project(&self, old: &EfgBody, fields: [&[f64]; 3]) -> Result<[Vec<f64>; 3], EfgError> {
        let mesh = self
            .mesh
            .as_ref()
            .ok_or_else(|| EfgError::Invalid("projection needs a polygon body".into()))?;
        let sub = self.spec.gauss.saturating_sub(3).max(1);
        let points = mesh.domain_points(sub);
        let t = self.material.thickness;
        let n = self.n_dofs();
        let mut rhs = [vec![0.0; n], vec![0.0; n], vec![0.0; n]];
        // per chunk: rows and the old fields in parallel, then summed in
        // point order (bitwise the same on any number of threads)
        const CHUNK: usize = 4096;
        for chunk in points.chunks(CHUNK) {
            let rows: Vec<Result<Projected, EfgError>> = chunk
                .par_iter()
                .map_init(ShapeRow::new, |old_row, q| {
                    let mut row = ShapeRow::new();
                    self.shape_row(q.x, &mut row)?;
                    old.shape_row(q.x, old_row)?;
                    let val = fields
                        .map(|f| [old_row.interpolate(f, 2, 0), old_row.interpolate(f, 2, 1)]);
                    Ok((row, val))
                })
                .collect();
            for (q, r) in chunk.iter().zip(rows) {
                let (row, val) = r?;
                let w = q.w * t;
                for (k, &i) in row.idx.iter().enumerate() {
                    let (i, phi) = (i as usize, row.phi[k] * w);
                    for (rf, v) in rhs.iter_mut().zip(&val) {
                        rf[2 * i] += phi * v[0];
                        rf[2 * i + 1] += phi * v[1];
                    }
                }
            }
        }
        let mut ch = Cholesky::factor(&self.ops.gram)?;
        for r in &mut rhs {
            ch.solve_in_place(r);
        }
        Ok(rhs)
    }
}
