//! The EFG body as seen by the coupling: contact chains along the body's
//! contact edges at their true displaced positions, and the [`Continuum`]
//! implementation (ERRATA E7: the same shape functions `φ_J(x_H)` give the
//! contact-point velocity and distribute the reaction).

use super::EfgError;
use super::body::EfgBody;
use super::shape::ShapeRow;
use crate::continuum::{BodyEnergies, BoundaryChain, Continuum, SolveError};
use crate::geom::Vec2;
use crate::scenario::body::Edge;
use std::cell::RefCell;

/// Edges in counter-clockwise order around the rectangle (body on the left).
const CCW: [Edge; 4] = [Edge::Bottom, Edge::Right, Edge::Top, Edge::Left];

/// Reference points along `edge`, counter-clockwise, `refine` points per
/// node spacing (both ends included).
fn edge_points(b: &EfgBody, edge: Edge, refine: usize) -> Vec<Vec2> {
    let (o, s) = (b.origin, b.size);
    let (a, e, n) = match edge {
        Edge::Bottom => (o, Vec2::new(o.x + s.x, o.y), b.grid[0]),
        Edge::Right => (Vec2::new(o.x + s.x, o.y), o + s, b.grid[1]),
        Edge::Top => (o + s, Vec2::new(o.x, o.y + s.y), b.grid[0]),
        Edge::Left => (Vec2::new(o.x, o.y + s.y), o, b.grid[1]),
    };
    let m = (n - 1) * refine;
    (0..=m)
        .map(|k| a + (e - a) * (k as f64 / m as f64))
        .collect()
}

/// Chains of reference points: consecutive listed edges (in CCW order)
/// are joined around their common corner; all four edges make one closed loop.
pub fn contact_chains(b: &EfgBody, edges: &[Edge], refine: usize) -> Vec<Vec<Vec2>> {
    let listed = |e: Edge| edges.contains(&e);
    let k0 = match (0..4).find(|&k| listed(CCW[k]) && !listed(CCW[(k + 3) % 4])) {
        Some(k) => k,
        None if edges.is_empty() => return Vec::new(),
        None => 0, // all four: a closed loop starting at the bottom edge
    };
    let mut chains: Vec<Vec<Vec2>> = Vec::new();
    let mut open = false;
    for k in k0..k0 + 4 {
        let e = CCW[k % 4];
        if !listed(e) {
            open = false;
            continue;
        }
        let pts = edge_points(b, e, refine);
        match chains.last_mut() {
            Some(c) if open => c.extend_from_slice(&pts[1..]),
            _ => chains.push(pts),
        }
        open = true;
    }
    chains
}

/// An [`EfgBody`] with its contact boundary: what the coupling drives.
pub struct EfgContinuum {
    pub body: EfgBody,
    chains: Vec<BoundaryChain>,
    /// Shape rows `φ_J(X)` of every chain point, per chain: (node, φ).
    rows: Vec<Vec<Vec<(u32, f64)>>>,
    scratch: RefCell<ShapeRow>,
    /// Rows of the points of the current implicit step.
    point_rows: Vec<Vec<(u32, f64)>>,
}

impl EfgContinuum {
    /// Wrap `body` with contact chains along `edges`, `refine` boundary
    /// points per node spacing. Shape rows of the chain points are computed
    /// once here.
    pub fn new(body: EfgBody, edges: &[Edge], refine: usize) -> Result<Self, EfgError> {
        let mut row = ShapeRow::new();
        let mut chains = Vec::new();
        let mut rows = Vec::new();
        for pts in contact_chains(&body, edges, refine.max(1)) {
            let mut r = Vec::with_capacity(pts.len());
            for &x in &pts {
                body.shape_row(x, &mut row)?;
                r.push(
                    row.idx
                        .iter()
                        .copied()
                        .zip(row.phi.iter().copied())
                        .collect(),
                );
            }
            rows.push(r);
            chains.push(BoundaryChain::new(pts));
        }
        let mut c = EfgContinuum {
            body,
            chains,
            rows,
            scratch: RefCell::new(ShapeRow::new()),
            point_rows: Vec::new(),
        };
        c.refresh();
        Ok(c)
    }

    /// Current chain positions `X + Σ φ_J(X) u_J` (true displacement, E7).
    pub fn refresh(&mut self) {
        let u = &self.body.state.u;
        for (chain, rows) in self.chains.iter_mut().zip(&self.rows) {
            for ((cur, x), row) in chain.current.iter_mut().zip(&chain.reference).zip(rows) {
                let mut d = Vec2::ZERO;
                for &(j, phi) in row {
                    d.x += phi * u[2 * j as usize];
                    d.y += phi * u[2 * j as usize + 1];
                }
                *cur = *x + d;
            }
        }
    }

    /// `Σ_J φ_J(x) a_J` of a nodal vector `a` (displacement or velocity).
    fn interpolate(&self, a: &[f64], x: Vec2) -> Vec2 {
        self.with_row(x, |row| {
            let mut s = Vec2::ZERO;
            for (&j, &phi) in row.idx.iter().zip(&row.phi) {
                s.x += phi * a[2 * j as usize];
                s.y += phi * a[2 * j as usize + 1];
            }
            s
        })
    }

    fn solve_error(&self, e: EfgError) -> SolveError {
        SolveError {
            body: self.body.name.clone(),
            message: e.to_string(),
        }
    }

    /// Shape row at a boundary material point (always covered: chain points
    /// were checked when the boundary was built, and a segment lies inside
    /// the supports covering its ends).
    fn with_row<R>(&self, x: Vec2, f: impl FnOnce(&ShapeRow) -> R) -> R {
        let mut row = self.scratch.borrow_mut();
        if self.body.shape_row(x, &mut row).is_err() {
            row.idx.clear();
            row.phi.clear();
        }
        f(&row)
    }
}

impl Continuum for EfgContinuum {
    fn name(&self) -> &str {
        &self.body.name
    }
    fn contact_boundary(&self) -> &[BoundaryChain] {
        &self.chains
    }
    /// Eq. (41) per ERRATA E7: `v_H = Σ_J φ_J(x_H) u̇_J`.
    fn boundary_velocity(&self, _chain: usize, x: Vec2) -> Vec2 {
        self.interpolate(&self.body.state.v, x)
    }
    fn boundary_displacement(&self, _chain: usize, x: Vec2) -> Vec2 {
        self.interpolate(&self.body.state.u, x)
    }
    /// Eq. (46) per ERRATA E7: `F += Φᵀ(x_H) f`.
    fn add_point_load(&mut self, _chain: usize, x: Vec2, f: Vec2) {
        let mut row = std::mem::take(&mut *self.scratch.borrow_mut());
        if self.body.shape_row(x, &mut row).is_ok() {
            self.body.add_point_load_row(&row, f);
        }
        *self.scratch.borrow_mut() = row;
    }
    /// Eqs. (46) and (49): the points' rows `φ_J(x_H)` (E7) give both the
    /// free displacements and the compliance `Φ A⁻¹ Φᵀ`.
    fn begin_step(
        &mut self,
        points: &[(usize, Vec2)],
        free: &mut Vec<Vec2>,
        compliance: &mut Vec<f64>,
    ) -> Result<(), SolveError> {
        let mut rows = std::mem::take(&mut self.point_rows);
        rows.clear();
        for &(_, x) in points {
            rows.push(self.with_row(x, |r| {
                r.idx.iter().copied().zip(r.phi.iter().copied()).collect()
            }));
        }
        let res = self
            .body
            .predict()
            .map(|nm| nm.point_compliance(&rows, free, compliance));
        self.point_rows = rows;
        res.map_err(|e| self.solve_error(e))
    }
    fn finish_step(&mut self, forces: &[Vec2]) -> Result<(), SolveError> {
        if let Some(nm) = self.body.newmark_mut() {
            nm.apply_point_forces(forces);
        }
        self.body.commit().map_err(|e| self.solve_error(e))?;
        self.refresh();
        Ok(())
    }
    fn energies(&self) -> BodyEnergies {
        BodyEnergies {
            kinetic: self.body.kinetic_energy(),
            strain: self.body.strain_energy(),
            work: self.body.motion_work
                + self
                    .body
                    .f_permanent
                    .iter()
                    .zip(&self.body.state.u)
                    .map(|(f, u)| f * u)
                    .sum::<f64>(),
        }
    }
    fn as_any(&self) -> &dyn std::any::Any {
        self
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn body() -> EfgBody {
        let src = r#"
            [simulation]
            analysis = "static"
            [[body]]
            name = "b"
            rectangle = { origin = [0.0, 0.0], size = [2.0, 1.0] }
            nodes = [5, 3]
            elastic = { E = 1000.0, nu = 0.3, density = 1.0 }
            [[body.bc]]
            edge = "left"
            fixed = true
        "#;
        let sc = crate::scenario::parse(src, "t.toml").unwrap();
        EfgBody::from_spec(&sc.body[0], [0.0, 0.0]).unwrap()
    }

    #[test]
    fn adjacent_edges_join_around_the_corner_counter_clockwise() {
        let b = body();
        let ch = contact_chains(&b, &[Edge::Top, Edge::Right], 1);
        assert_eq!(ch.len(), 1);
        // right edge bottom→top (3 points), then top right→left (5, corner shared)
        assert_eq!(ch[0].len(), 3 + 5 - 1);
        assert_eq!(ch[0][0], Vec2::new(2.0, 0.0));
        assert_eq!(ch[0][2], Vec2::new(2.0, 1.0));
        assert_eq!(*ch[0].last().unwrap(), Vec2::new(0.0, 1.0));
        // opposite edges stay separate; wrap-around left+bottom joins
        assert_eq!(contact_chains(&b, &[Edge::Top, Edge::Bottom], 1).len(), 2);
        let lb = contact_chains(&b, &[Edge::Left, Edge::Bottom], 2);
        assert_eq!(lb.len(), 1);
        assert_eq!(lb[0][0], Vec2::new(0.0, 1.0));
        assert_eq!(lb[0].len(), 5 + 9 - 1);
        let all = contact_chains(&b, &[Edge::Left, Edge::Bottom, Edge::Right, Edge::Top], 1);
        assert_eq!(all.len(), 1);
        assert_eq!(all[0].first(), all[0].last());
    }

    #[test]
    fn chain_follows_the_true_displacement_and_loads_are_work_consistent() {
        let mut c = EfgContinuum::new(body(), &[Edge::Top], 3).unwrap();
        // a linear field u = (0.01 y, 0.02 x) is reproduced exactly by MLS:
        // set nodal parameters to it and the chain must move accordingly
        for i in 0..c.body.n_nodes() {
            let x = c.body.node(i);
            c.body.state.u[2 * i] = 0.01 * x.y;
            c.body.state.u[2 * i + 1] = 0.02 * x.x;
            c.body.state.v[2 * i] = -0.5;
            c.body.state.v[2 * i + 1] = 0.25 * x.x;
        }
        c.refresh();
        let ch = &c.contact_boundary()[0];
        for (x, cur) in ch.reference.iter().zip(&ch.current) {
            let exact = *x + Vec2::new(0.01 * x.y, 0.02 * x.x);
            assert!((*cur - exact).norm() < 1e-12);
        }
        let p = Vec2::new(0.7, 1.0);
        let v = c.boundary_velocity(0, p);
        assert!((v - Vec2::new(-0.5, 0.25 * 0.7)).norm() < 1e-12);
        // power of a point load = f · v_H, through the same φ_J
        let f = Vec2::new(3.0, -2.0);
        c.add_point_load(0, p, f);
        let power: f64 = c
            .body
            .f_point
            .iter()
            .zip(&c.body.state.v)
            .map(|(a, b)| a * b)
            .sum();
        assert!((power - f.dot(v)).abs() < 1e-12);
    }
}
