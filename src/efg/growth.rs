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
//! **The energy.** The carried state is continuous across the new piece,
//! so it still holds the tractions the cut removed; the new piece opens
//! at once: the body relaxes to balance under its loads at the present
//! time, its velocity and acceleration kept (no time passes), held by the
//! disc contacts of a coupled run as springs with the discs in place
//! ([`HeldContact`]). Each growth books in
//! [`EfgBody::fracture_energy`] what the body and those springs lost: the
//! drop of its stored energy (kinetic, strain, penalty) less the work of
//! its loads, plus the energy the springs gave up. In a static analysis
//! at fixed loads this is Griffith's `Π(a) − Π(a + Δa) = ∫ G t da`
//! (`G = (K_I² + K_II²)/E′`, Irwin; the criterion's own estimate
//! `G Δa t` is [`Growth::released`]).

use super::EfgError;
use super::body::EfgBody;
use super::fracture::Tip;
use super::penalty::When;
use super::shape::ShapeRow;
use crate::continuum::crack_tip::{e_prime, energy_release_rate, max_hoop_stress};
use crate::continuum::{HeldContact, Plane};
use crate::geom::Vec2;
use crate::geom::polygon::segments_meet;
use crate::sparse::{Cholesky, SymCsc};
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
    /// Irwin's estimate of the energy released, `G Δa t` with `G` at the
    /// old tip (the growth books what the body lost,
    /// [`EfgBody::fracture_energy`]).
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

    /// [`grow`](Self::grow) for a body held by the disc contacts `held`
    /// (their forces of the present state, and their normal springs with
    /// the discs held in place): the new pieces open against them
    /// (module doc, *the energy*).
    pub fn grow_under(&mut self, held: &[HeldContact]) -> Result<Vec<Growth>, EfgError> {
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
        let springs = new.hold(held);
        let given = new.release(&springs)?;
        new.fracture_energy =
            self.fracture_energy + self.energy_less_work() - new.energy_less_work() + given;
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
    pub fn grow_if_due(&mut self, held: &[HeldContact]) -> Result<Vec<Growth>, EfgError> {
        if self.growth_due() {
            self.grow_under(held)
        } else {
            Ok(Vec::new())
        }
    }

    /// Whether the step count is a multiple of the fracture's `every`
    /// (false without fracture).
    pub fn growth_due(&self) -> bool {
        self.spec
            .fracture
            .is_some_and(|f| self.step.is_multiple_of(f.every.max(1)))
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

    /// The contacts `held` on the body: their forces into the pending
    /// point loads, and their springs `(k_n, Φᵀn)` (the sparse functional
    /// of the normal motion of the point). As the coupling's rows: a point
    /// no node covers carries nothing.
    fn hold(&mut self, held: &[HeldContact]) -> Vec<(f64, Vec<(usize, f64)>)> {
        let mut row = ShapeRow::new();
        let mut springs = Vec::new();
        for h in held {
            if self.shape_row(h.point, &mut row).is_err() {
                continue;
            }
            self.add_point_load_row(&row, h.force);
            if h.kn > 0.0 {
                let b = row.idx.iter().zip(&row.phi).flat_map(|(&i, &phi)| {
                    [
                        (2 * i as usize, phi * h.normal.x),
                        (2 * i as usize + 1, phi * h.normal.y),
                    ]
                });
                springs.push((h.kn, b.collect()));
            }
        }
        springs
    }

    /// Let a body just carried over from a body with shorter cracks open
    /// its new pieces (module doc, *the energy*): the carried state is
    /// continuous across them, so it is out of balance by the tractions
    /// the cut removed, `r = F − K̄U − MÜ − CU̇` (`F` the body's loads at the
    /// present time, with the pending point loads of the holding
    /// contacts); the body relaxes by `ΔU = (K̄ + Σ k_n bbᵀ)⁻¹ r` (`b = Φᵀn`
    /// of each holding contact's spring, the discs held in place), its
    /// velocity and acceleration kept, and is in balance again. The timed
    /// loads' work on `ΔU` is booked with them; the point loads are then
    /// cleared. Returns the energy the contacts' springs gave up,
    /// `fᵀΔU − ½ Σ k_n (bᵀΔU)²` (the work of their present forces less
    /// what their springs took back).
    fn release(&mut self, springs: &[(f64, Vec<(usize, f64)>)]) -> Result<f64, EfgError> {
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
        let du = held_solve(&kbar, springs, r)?;
        let dot = |a: &[f64]| a.iter().zip(&du).map(|(x, y)| x * y).sum::<f64>();
        self.load_work += dot(&timed);
        let taken: f64 = springs
            .iter()
            .map(|(k, b)| 0.5 * k * along(b, &du).powi(2))
            .sum();
        let given = dot(&self.f_point) - taken;
        for (u, d) in self.state.u.iter_mut().zip(&du) {
            *u += d;
        }
        self.f_point.iter_mut().for_each(|x| *x = 0.0);
        Ok(given)
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

/// `bᵀx` of a spring's sparse functional `b` (the normal motion of its
/// point).
fn along(b: &[(usize, f64)], x: &[f64]) -> f64 {
    b.iter().map(|&(i, v)| v * x[i]).sum()
}

/// `x = (K̄ + Σ k bbᵀ)⁻¹ r` for the springs `(k, b)`: conjugate gradients
/// preconditioned with `K̄⁻¹` (one factorisation). The preconditioned
/// operator is the identity plus a term of rank `m` (the number of
/// springs), so the iteration ends in at most `m + 1` steps in exact
/// arithmetic; without springs it is the one solve `K̄⁻¹ r`.
fn held_solve(
    kbar: &SymCsc,
    springs: &[(f64, Vec<(usize, f64)>)],
    mut r: Vec<f64>,
) -> Result<Vec<f64>, EfgError> {
    let mut chol = Cholesky::factor(kbar)?;
    let precondition = |chol: &mut Cholesky, r: &[f64]| {
        let mut z = r.to_vec();
        chol.solve_in_place(&mut z);
        z
    };
    let dot = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(x, y)| x * y).sum::<f64>();
    let mut x = precondition(&mut chol, &r);
    if springs.is_empty() {
        return Ok(x);
    }
    let apply = |x: &[f64]| {
        let mut y = vec![0.0; x.len()];
        kbar.mul_add(x, &mut y);
        for (k, b) in springs {
            let s = k * along(b, x);
            b.iter().for_each(|&(i, v)| y[i] += s * v);
        }
        y
    };
    // r − A x with x = K̄⁻¹ r: the springs' forces alone
    let ax = apply(&x);
    r.iter_mut().zip(&ax).for_each(|(r, a)| *r -= a);
    let mut z = precondition(&mut chol, &r);
    let mut p = z.clone();
    let mut rz = dot(&r, &z);
    let rz0 = rz;
    for _ in 0..=2 * springs.len() {
        if rz <= 1e-24 * rz0 || rz == 0.0 {
            break;
        }
        let q = apply(&p);
        let alpha = rz / dot(&p, &q);
        x.iter_mut().zip(&p).for_each(|(x, p)| *x += alpha * p);
        r.iter_mut().zip(&q).for_each(|(r, q)| *r -= alpha * q);
        z = precondition(&mut chol, &r);
        let rz_new = dot(&r, &z);
        let beta = rz_new / rz;
        p.iter_mut().zip(&z).for_each(|(p, z)| *p = z + beta * *p);
        rz = rz_new;
    }
    Ok(x)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::continuum::{BodyParams, Edge, EdgeCondition, Elastic, Rectangle};

    /// The held solve meets `(K̄ + Σ k bbᵀ) x = r` to round-off with
    /// springs both softer and far stiffer than the body.
    #[test]
    fn held_solve_solves_the_body_with_its_springs() {
        let mut p = BodyParams::new(
            "b",
            Rectangle {
                origin: [0.0, 0.0],
                size: [2.0, 1.0],
            },
            [9, 5],
            Elastic::new(1000.0, 0.3).density(1.0),
        );
        p.bc.push(EdgeCondition::fixed(Edge::Left));
        let mut b = EfgBody::new(&p, [0.0, 0.0]).unwrap();
        let held: Vec<HeldContact> = [(0.7, 1.0e2), (1.3, 1.0e7), (2.0, 5.0)]
            .iter()
            .map(|&(x, kn)| HeldContact {
                point: Vec2::new(x, 1.0),
                force: Vec2::new(0.0, -1.0),
                normal: Vec2::new(0.3, -1.0) * (1.0 / 1.09f64.sqrt()),
                kn,
            })
            .collect();
        let springs = b.hold(&held);
        assert_eq!(springs.len(), 3);
        let kbar = b.ops.kbar();
        let r: Vec<f64> = (0..b.n_dofs())
            .map(|i| ((i * 7) % 5) as f64 - 2.0)
            .collect();
        let x = held_solve(&kbar, &springs, r.clone()).unwrap();
        let mut ax = vec![0.0; x.len()];
        kbar.mul_add(&x, &mut ax);
        for (k, s) in &springs {
            let d = k * along(s, &x);
            s.iter().for_each(|&(i, v)| ax[i] += d * v);
        }
        let norm = |a: &[f64]| a.iter().map(|v| v * v).sum::<f64>().sqrt();
        let res: Vec<f64> = ax.iter().zip(&r).map(|(a, r)| a - r).collect();
        assert!(norm(&res) < 1e-9 * norm(&r), "{:e}", norm(&res) / norm(&r));
        // the stiff spring holds its point: its normal motion is tiny
        let (stiff, soft) = (along(&springs[1].1, &x), along(&springs[0].1, &x));
        assert!(stiff.abs() < 1e-3 * soft.abs(), "{stiff:e} vs {soft:e}");
    }
}
