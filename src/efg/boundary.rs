//! The EFG body as seen by the coupling: [`EfgContinuum`], the body with
//! contact chains along its contact edges at their true displaced positions
//! (ERRATA E7: the same shape functions `φ_J(x_H)` give the contact-point
//! velocity and distribute the reaction).

use super::EfgError;
use super::body::EfgBody;
use super::shape::ShapeRow;
use crate::continuum::newmark::{Newmark, State};
use crate::continuum::{
    BodyEnergies, BodyState, ContactBody, Edge, HeldContact, Row, StateError, WithBoundary,
    add_dof_load, add_row_load,
};
use crate::geom::Vec2;

/// An [`EfgBody`] with its contact boundary: what the coupling drives.
pub type EfgContinuum = WithBoundary<EfgBody>;

impl EfgBody {
    /// The contact chains of a polygon body (`None` for a rectangle): along
    /// the named edges `names` (all loops if `None`), through the boundary
    /// points (nodes and vertices) with `refine` points per piece between them, body on the left
    /// (holes run clockwise). Consecutive segments of a loop join into one
    /// chain; a whole loop is one closed chain. An edge crack's faces are on
    /// the chain of its mouth's loop; a crack with two tips is a closed
    /// chain of its own (`crack_loop`), whatever `names`. Unknown names
    /// are an error.
    pub fn polygon_chains(
        &self,
        names: Option<&[crate::continuum::EdgeName]>,
        refine: usize,
    ) -> Option<Result<Vec<Vec<Vec2>>, EfgError>> {
        let m = self.mesh.as_ref()?;
        let refine = refine.max(1);
        let mut on: Vec<Vec<bool>> = m
            .segment_points
            .iter()
            .map(|s| vec![names.is_none(); s.len()])
            .collect();
        for n in names.unwrap_or(&[]) {
            let Some(e) = m.domain.edge(n.as_str()) else {
                return Some(Err(EfgError::Invalid(format!(
                    "body `{}`: unknown edge `{n}`",
                    self.name
                ))));
            };
            for &(l, s) in &e.segments {
                on[l][s] = true;
            }
        }
        // a point's reference position: a face node's own (off the crack,
        // on its face), so that its row is its face's
        let pos = |i: usize| m.nodes.get(i).copied().unwrap_or(m.points[i]);
        let detours = mouth_detours(m);
        // points from `a` towards `b` (excluded), `refine` per piece
        let piece = |cur: &mut Vec<Vec2>, a: Vec2, b: Vec2| {
            for j in 0..refine {
                cur.push(a + (b - a) * (j as f64 / refine as f64));
            }
        };
        // from the face node `e` into a crack along one face, out along
        // the other to the face node `start`
        let round = |cur: &mut Vec<Vec2>, e: usize, way: &[Vec2], start: usize| {
            let mut a = pos(e);
            for &b in way {
                piece(cur, a, b);
                a = b;
            }
            piece(cur, a, pos(start));
        };
        let mut chains = Vec::new();
        for (l, segs) in m.segment_points.iter().enumerate() {
            let n = segs.len();
            let sel = &on[l];
            // start after an unselected segment (or at 0 for a whole loop)
            let Some(k0) = (0..n)
                .find(|&k| sel[k] && !sel[(k + n - 1) % n])
                .or(sel[0].then_some(0))
            else {
                continue;
            };
            let mut cur: Vec<Vec2> = Vec::new();
            let mut last: Option<usize> = None; // the previous segment's end
            for t in 0..n {
                let k = (k0 + t) % n;
                if !sel[k] {
                    if !cur.is_empty() {
                        chains.push(std::mem::take(&mut cur));
                    }
                    last = None;
                    continue;
                }
                let start = segs[k][0];
                if let Some(e) = last {
                    cur.pop(); // the previous segment's end: again below
                    if let Some(d) = detours.get(&(e, start)) {
                        round(&mut cur, e, d, start);
                    }
                }
                for w in segs[k].windows(2) {
                    piece(&mut cur, pos(w[0]), pos(w[1]));
                }
                let end = *segs[k].last().expect("a segment has 2 points");
                cur.push(pos(end));
                last = Some(end);
            }
            // a whole loop that starts at a crack's mouth closes through it
            if let Some(e) = last
                && (0..n).all(|k| sel[k])
                && let Some(d) = detours.get(&(e, segs[0][0]))
            {
                cur.pop();
                round(&mut cur, e, d, segs[0][0]);
                cur.push(cur[0]);
            }
            if !cur.is_empty() {
                chains.push(cur);
            }
        }
        for c in &m.cracks {
            if let Some(way) = crack_loop(m, c) {
                let mut cur = Vec::new();
                for w in way.windows(2) {
                    piece(&mut cur, w[0], w[1]);
                }
                cur.push(way[0]);
                chains.push(cur);
            }
        }
        Some(Ok(chains))
    }
}

/// The way round a crack with two tips (none for an edge crack), body on
/// the left: from the first tip along the left face's nodes to the other
/// tip, back along the right face's to the first (first point = last).
/// It encloses no area; its outward normals point from each face into the
/// crack, where discs can only be when the crack is open.
fn crack_loop(
    m: &super::polygon::PolygonMesh,
    c: &super::polygon::CrackNodes,
) -> Option<Vec<Vec2>> {
    use crate::geom::crack::End;
    if c.ends.iter().any(|e| *e != End::Tip) {
        return None;
    }
    let last = c.nodes.len() - 1;
    let left = (0..=last).map(|k| c.nodes[k][0]);
    let right = (0..last).rev().map(|k| c.nodes[k][1]);
    Some(left.chain(right).map(|i| m.nodes[i]).collect())
}

/// The way round each crack mouth of a polygon mesh, keyed by the face
/// nodes the outline reaches it with and leaves it from (the end of the
/// segment before the mouth, the start of the one after): the face nodes
/// of the face on the side the outline comes from, from the mouth to the
/// tip, then those of the other face back to the mouth (the mouth's own
/// two excluded). The outline goes round the crack with the body on its
/// left, as it goes round the body.
fn mouth_detours(
    m: &super::polygon::PolygonMesh,
) -> std::collections::HashMap<(usize, usize), Vec<Vec2>> {
    use crate::geom::crack::End;
    let starts: std::collections::HashSet<usize> =
        m.segment_points.iter().flatten().map(|s| s[0]).collect();
    let mut out = std::collections::HashMap::new();
    for c in &m.cracks {
        let last = c.nodes.len() - 1;
        for (e, j) in [(0, 0), (1, last)] {
            if !matches!(c.ends[e], End::Mouth(..)) {
                continue;
            }
            let pair = c.nodes[j];
            // the node that starts the segment after the mouth
            let after = usize::from(starts.contains(&pair[1]));
            let before = 1 - after;
            let inward: Vec<usize> = if j == 0 {
                (1..=last).collect()
            } else {
                (0..last).rev().collect()
            };
            let node = |i: usize| m.nodes[i];
            let mut way: Vec<Vec2> = inward.iter().map(|&k| node(c.nodes[k][before])).collect();
            way.extend(
                inward
                    .iter()
                    .rev()
                    .skip(1)
                    .map(|&k| node(c.nodes[k][after])),
            );
            out.insert((pair[before], pair[after]), way);
        }
    }
    out
}

impl ContactBody for EfgBody {
    type Error = EfgError;
    fn name(&self) -> &str {
        &self.name
    }
    fn grid(&self) -> (Vec2, Vec2, [usize; 2]) {
        (self.origin, self.size, self.grid)
    }
    /// Rectangles: [`crate::continuum::contact_chains`] along `edges`. A
    /// polygon body: every loop (outline and holes) is one closed chain
    /// (body on its left), through the boundary nodes with `refine` points
    /// per piece between them; `edges` is ignored.
    fn chains(&self, edges: &[Edge], refine: usize) -> Vec<Vec<Vec2>> {
        match self.polygon_chains(None, refine) {
            Some(Ok(c)) => c,
            _ => crate::continuum::contact_chains(self.origin, self.size, self.grid, edges, refine),
        }
    }
    /// A polygon body: [`EfgBody::polygon_chains`] along `names`.
    fn named_chains(
        &self,
        names: Option<&[crate::continuum::EdgeName]>,
        edges: &[Edge],
        refine: usize,
    ) -> Result<Vec<Vec<Vec2>>, EfgError> {
        match self.polygon_chains(names, refine) {
            Some(c) => c,
            None => Ok(self.chains(edges, refine)),
        }
    }
    /// The MLS shape functions `φ_J(x)` (E7).
    fn row(&self, x: Vec2) -> Result<Row, EfgError> {
        let mut r = ShapeRow::new();
        self.shape_row(x, &mut r)?;
        Ok(r.idx.iter().copied().zip(r.phi.iter().copied()).collect())
    }
    fn start_dynamic(&mut self, dt: f64) -> Result<(), EfgError> {
        EfgBody::start_dynamic(self, dt)
    }
    fn retime(&mut self, dt: f64, scale: (usize, usize)) -> Result<(), EfgError> {
        EfgBody::retime(self, dt, scale)
    }
    fn state(&self) -> &State {
        &self.state
    }
    fn add_point_load_row(&mut self, row: &[(u32, f64)], f: Vec2) {
        add_row_load(&mut self.f_point, row, f);
    }
    fn predict(&mut self) -> Result<&mut Newmark, EfgError> {
        EfgBody::predict(self)
    }
    fn newmark_mut(&mut self) -> Option<&mut Newmark> {
        EfgBody::newmark_mut(self)
    }
    fn add_point_forces(&mut self, rows: &[Vec<(usize, f64)>], f: &[Vec2]) -> Result<(), EfgError> {
        EfgBody::add_point_forces(self, rows, f)
    }
    fn solve_pending(&self) -> bool {
        self.refinement_pending()
    }
    fn add_dof_loads(&mut self, row: &[(usize, f64)], g: f64) {
        add_dof_load(&mut self.f_point, row, g);
    }
    fn set_contact_force(&mut self, f: Vec2) {
        self.contact_force = f;
    }
    fn commit(&mut self) -> Result<(), EfgError> {
        EfgBody::commit(self)
    }
    /// [`EfgBody::grow_if_due`].
    fn grow(&mut self, held: &[HeldContact]) -> Result<bool, EfgError> {
        Ok(!self.grow_if_due(held)?.is_empty())
    }
    fn growth_due(&self) -> bool {
        EfgBody::growth_due(self)
    }
    fn grows(&self) -> bool {
        self.spec.fracture.is_some()
    }
    fn book_fracture(&mut self, e: f64) {
        self.fracture_energy += e;
    }
    fn save_state(&self) -> BodyState {
        EfgBody::save_state(self)
    }
    fn restore_state(&mut self, s: &BodyState) -> Result<(), StateError> {
        EfgBody::restore_state(self, s)
    }
    fn energies(&self) -> BodyEnergies {
        BodyEnergies {
            kinetic: self.kinetic_energy(),
            strain: self.elastic_energy(),
            penalty: self.penalty_energy(),
            // constant loads from U = 0 (the penalty load is in `penalty`),
            // plus the work of the moving edges
            work: self.motion_work
                + self.load_work
                + self
                    .f_permanent
                    .iter()
                    .zip(&self.state.u)
                    .map(|(f, u)| f * u)
                    .sum::<f64>(),
            fracture: self.fracture_energy,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::continuum::{BodyParams, Continuum, Edge, EdgeCondition, Elastic, Rectangle};

    fn body() -> EfgBody {
        let mut p = BodyParams::new(
            "b",
            Rectangle {
                origin: [0.0, 0.0],
                size: [2.0, 1.0],
            },
            [5, 3],
            Elastic::new(1000.0, 0.3).density(1.0),
        );
        p.bc.push(EdgeCondition::fixed(Edge::Left));
        EfgBody::new(&p, [0.0, 0.0]).unwrap()
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
