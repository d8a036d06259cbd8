//! [`EfgBody`]: one EFG continuum on a rectangular node grid, built from a
//! [`BodyParams`]: nodes, supports, assembled operators, loads, state, and
//! what the coupling needs (true sampling, shape rows, point loads, Newmark
//! advance).

use super::EfgError;
use super::assemble::{self, Operators, PointRole, PointShapes};
use super::face_contact::{FaceContact, Law};
use super::penalty::{MovingEdge, When};
use super::polygon::PolygonMesh;
use super::shape::{ShapeRow, shape_functions};
use super::support::Support;
use crate::continuum::conditions::{
    constrained, edge_ends, prescribed, timoshenko_of, traction_at, traction_normal,
};
use crate::continuum::material::energy_error_of;
use crate::continuum::newmark::{Newmark, NewmarkParams, State};
use crate::continuum::quadrature::{self, QuadPoint};
use crate::continuum::timoshenko::Timoshenko;
use crate::continuum::{
    BodyParams, BodyState, CrackState, Drive, DriveState, Edge, Material, Measure, Sample,
    StateError, TimedLoad,
};
use crate::geom::Vec2;
use crate::geom::crack::Crack;
use crate::sparse::{Cholesky, RowSelection, SymCsc};
use std::time::Instant;

/// Sizes and timings of a build, for `check` and summaries.
#[derive(Debug, Clone, Default, serde::Serialize)]
pub struct BuildInfo {
    /// Number of nodes.
    pub nodes: usize,
    /// Number of unknowns, 2 per node.
    pub dofs: usize,
    /// Gauss points of the background cells (domain integrals, Eqs. 23–25).
    pub domain_points: usize,
    /// Gauss points on Γu (penalty integrals, Eqs. 26 and 28 per E4).
    pub boundary_points: usize,
    /// Fewest nodes whose support covers a quadrature point.
    pub min_cover: usize,
    /// Most nodes whose support covers a quadrature point.
    pub max_cover: usize,
    /// Stored entries of the lower triangle of K̄.
    pub nnz: usize,
    /// Wall time of the shape functions at all quadrature points (s).
    pub shape_seconds: f64,
    /// Wall time of the assembly of K̄ and G (s).
    pub assembly_seconds: f64,
}

/// An element-free Galerkin body.
#[derive(Debug)]
pub struct EfgBody {
    /// Name (for messages and outputs).
    pub name: String,
    /// Node grid `[nx, ny]`; node `(i, j)` is `j·nx + i` at `(xs[i], ys[j])`.
    pub grid: [usize; 2],
    /// The nodes and integration triangles of a polygon body (then `grid`
    /// is `[0, 0]` and `xs`, `ys` are empty).
    pub mesh: Option<PolygonMesh>,
    /// x of the node columns, ascending (reference configuration).
    pub xs: Vec<f64>,
    /// y of the node rows, ascending (reference configuration).
    pub ys: Vec<f64>,
    /// Lower-left corner of the rectangle.
    pub origin: Vec2,
    /// Width and height of the rectangle.
    pub size: Vec2,
    /// Nodes and their rectangular supports `d_mx`, `d_my` (Eqs. 7–8).
    pub support: Support,
    /// Elastic constants, density, thickness, damping and `D`.
    pub material: Material,
    /// Support size factor `d_max` (Eqs. 7–8).
    pub d_max: f64,
    /// K, Gram matrix G (M = ρG, C = cG), ∫φ t, and the penalty points
    /// (`K̄ = K + K^α`, `F^α(t)`, moving edges; E4).
    pub ops: Operators,
    /// Loads present throughout: permanent tractions and body force
    /// (Eq. 27). The penalty load `F^α(t)` (Eq. 28 / E4) is added to each
    /// solve from [`Operators::penalty`].
    pub f_permanent: Vec<f64>,
    /// Loads named in `initial.static_under`: applied for the initial static
    /// state only, released at t = 0.
    pub f_released: Vec<f64>,
    /// Point loads accumulated for the next step (Eq. 46), cleared by `advance`.
    pub f_point: Vec<f64>,
    /// Loads that change in time (tractions and point loads with a
    /// `table`): `F(t) = f_permanent + Σ_k s_k(t) F_k`.
    pub timed: Vec<TimedLoad>,
    /// Work of the timed loads since t = 0 (trapezoidal in time).
    pub load_work: f64,
    /// Total force of the discs on the body at the present state (set by
    /// the coupling before each step; what a servo with `measure =
    /// "contacts"` measures).
    pub contact_force: Vec2,
    /// Scratch of [`refine_residual`](Self::refine_residual): the residual
    /// (loads without `F^α` on entry), `U₊`, `−Ü₊`, `−U̇₊` (damped bodies),
    /// `−U₊`.
    refine_work: [Vec<f64>; 5],
    /// The refinement residual of the present step awaits its solve (at
    /// [`commit`](Self::commit), or folded into the contact forces' solve).
    refine_pending: bool,
    /// The penalty rows the refinement computes its residual on, with the
    /// values of M, C (if any) and K on them.
    refine_rows: Option<RowSelection>,
    /// Work done on the body by the moving edges since t = 0.
    pub motion_work: f64,
    /// Nodal parameters (not nodal displacements: no Kronecker-delta property).
    pub state: State,
    /// Time reached, `step · Δt`.
    pub time: f64,
    /// Steps done.
    pub step: usize,
    /// Δt (0 until the dynamic start), γ, β.
    pub params: NewmarkParams,
    newmark: Option<Newmark>,
    /// The Timoshenko field if a bc uses it (for error norms and summaries).
    pub timoshenko: Option<Timoshenko>,
    /// Sizes and timings of the build.
    pub info: BuildInfo,
    /// The parameters the body was built from (its cracks as they are
    /// now): a growing crack rebuilds the body from them.
    pub spec: BodyParams,
    /// `[simulation] gravity` of the build.
    pub gravity: [f64; 2],
    /// Energy crack growth took since t = 0: at each growth the drop of
    /// the stored energy less the load work as the new pieces open (with
    /// the holding contacts' springs; [`super::growth`], *the energy*) —
    /// at fixed loads `∫ G t da`, `G = (K_I² + K_II²)/E′`.
    pub fracture_energy: f64,
    /// Growth increments so far, per crack tip `[crack][end]`.
    pub increments: Vec<[usize; 2]>,
    /// Contact of the crack faces (empty without cracks).
    pub faces: FaceContact,
}

impl EfgBody {
    /// Build the body: node grid, supports, quadrature, shape functions at
    /// all quadrature points (parallel), operators K̄, G (parallel,
    /// thread-count independent), and load vectors. `gravity` is the
    /// acceleration of `[simulation] gravity`.
    pub fn new(spec: &BodyParams, gravity: [f64; 2]) -> Result<EfgBody, EfgError> {
        let invalid = |m: String| EfgError::Invalid(format!("body `{}`: {m}", spec.name));
        let el = spec.elastic;
        let material = Material::of_params(spec);
        let t = el.thickness;
        let alpha = spec.penalty.unwrap_or(1e5 * el.e);
        let n = spec.gauss;
        let timoshenko = timoshenko_of(spec);
        let origin = Vec2::from(spec.rectangle.origin);
        let size = Vec2::from(spec.rectangle.size);
        // nodes, supports, domain quadrature, and per bc its boundary
        // pieces (a, b, outward normal, sub-segments)
        // (a, b, outward normal, sub-segments, Gauss points per sub-segment)
        type Pieces = Vec<(Vec2, Vec2, Option<Vec2>, usize, usize)>;
        let cracked_rectangle = (spec.polygon.is_none() && !spec.cracks.is_empty())
            .then(|| rectangle_polygon(&spec.rectangle, spec.nodes))
            .transpose()
            .map_err(invalid)?;
        let (xs, ys, support, domain, mesh, pieces): (_, _, _, _, _, Vec<Pieces>) = if let Some(
            poly,
        ) =
            spec.polygon.as_ref().or(cracked_rectangle.as_ref())
        {
            let mesh = PolygonMesh::cracked(
                &poly.domain,
                poly.spacing,
                &poly.refine,
                &spec.cracks,
                spec.d_max,
            )
            .map_err(invalid)?;
            let node: Vec<[f64; 4]> = mesh
                .nodes
                .iter()
                .zip(&mesh.node_spacing)
                .map(|(p, h)| [p.x, p.y, spec.d_max * h, spec.d_max * h])
                .collect();
            let opaque: Vec<_> = mesh.cracks.iter().map(|c| c.opaque()).collect();
            let support = Support::new(node).with_cracks(&mesh.domain, &opaque, true);
            let poly_domain = &mesh.domain;
            let domain = mesh.domain_points(n.saturating_sub(3).max(1));
            let mut pieces = Vec::with_capacity(spec.bc.len());
            for bc in &spec.bc {
                let Some(e) = poly_domain.edge(bc.edge.as_str()) else {
                    return Err(invalid(format!(
                        "unknown edge `{}` (the polygon's named edges: {})",
                        bc.edge,
                        poly_domain
                            .edges
                            .iter()
                            .map(|e| e.name.as_str())
                            .collect::<Vec<_>>()
                            .join(", ")
                    )));
                };
                if bc.parabolic_shear.is_some() || bc.timoshenko.is_some() {
                    return Err(invalid(format!(
                        "bc on `{}`: parabolic_shear and timoshenko are for rectangular bodies without cracks only",
                        bc.edge
                    )));
                }
                // a piece that only follows a boundary finer than the nodes
                // (it ends at a vertex that is not a node) is short: one
                // Gauss point
                pieces.push(
                    mesh.pieces(&e.segments)
                        .into_iter()
                        .map(|(a, b, fine)| {
                            let d = b - a;
                            let g = if fine { 1 } else { n };
                            (a, b, Some(Vec2::new(d.y, -d.x) * (1.0 / d.norm())), 1, g)
                        })
                        .collect(),
                );
            }
            (Vec::new(), Vec::new(), support, domain, Some(mesh), pieces)
        } else {
            let [nx, ny] = spec.nodes;
            if nx < 2 || ny < 2 {
                return Err(EfgError::Invalid(format!(
                    "body `{}`: the node grid needs at least 2 × 2 nodes",
                    spec.name
                )));
            }
            let xs: Vec<f64> = (0..nx)
                .map(|i| origin.x + size.x * i as f64 / (nx - 1) as f64)
                .collect();
            let ys: Vec<f64> = (0..ny)
                .map(|j| origin.y + size.y * j as f64 / (ny - 1) as f64)
                .collect();
            let support = Support::for_grid(&xs, &ys, spec.d_max);
            let cells = spec.cells.unwrap_or([nx - 1, ny - 1]);
            let segs = |e: Edge| match e {
                Edge::Left | Edge::Right => cells[1],
                Edge::Top | Edge::Bottom => cells[0],
            };
            let domain = quadrature::domain_points(origin, size, cells, n);
            let mut pieces = Vec::with_capacity(spec.bc.len());
            for bc in &spec.bc {
                let e = bc.side().map_err(invalid)?;
                let (a, b) = edge_ends(origin, size, e);
                pieces.push(vec![(a, b, None, segs(e), n)]);
            }
            (xs, ys, support, domain, None, pieces)
        };
        // quadrature points: domain, then penalty points of each Γu bc
        let mut points: Vec<Vec2> = domain.iter().map(|q| q.x).collect();
        let mut roles: Vec<PointRole> = domain.iter().map(|q| PointRole::Domain(q.w * t)).collect();
        let mut penalty_values: Vec<[f64; 2]> = Vec::new();
        let mut penalty_bc: Vec<usize> = Vec::new();
        for (bi, bc) in spec.bc.iter().enumerate().filter(|(_, b)| !b.is_load()) {
            let (cx, cy) = constrained(bc);
            for &(a, b, _, m, g) in &pieces[bi] {
                for q in quadrature::edge_points(a, b, m, g) {
                    points.push(q.x);
                    let w = q.w * t * alpha;
                    roles.push(PointRole::Penalty(
                        if cx { w } else { 0.0 },
                        if cy { w } else { 0.0 },
                    ));
                    penalty_values.push(prescribed(bc, q.x, timoshenko.as_ref(), &el));
                    penalty_bc.push(bi);
                }
            }
        }
        let t0 = Instant::now();
        let shapes = assemble::point_shapes(&support, &points)
            .map_err(|e| EfgError::coverage(e, spec.d_max, &spec.name))?;
        let shape_seconds = t0.elapsed().as_secs_f64();
        let t1 = Instant::now();
        let mut ops = assemble::assemble(support.len(), &shapes, &roles, material.d);
        let assembly_seconds = t1.elapsed().as_secs_f64();
        let ndof = 2 * support.len();
        // prescribed values ū(x_g) of the penalty points (E4), and the
        // moving edges: ū_c(t) = d(t) on their points (contiguous per bc)
        let nd = domain.len();
        for (k, ub) in penalty_values.iter().enumerate() {
            ops.penalty.set_value(k, *ub);
        }
        for (bi, bc) in spec.bc.iter().enumerate() {
            let (Some(first), Some(last)) = (
                penalty_bc.iter().position(|&b| b == bi),
                penalty_bc.iter().rposition(|&b| b == bi),
            ) else {
                continue;
            };
            for (component, pr) in [(0, &bc.ux), (1, &bc.uy)] {
                let Some(pr) = pr.as_ref() else { continue };
                if let Some(law) = pr.drive_law() {
                    let scale = match pr {
                        crate::continuum::Prescribed::ScaledLinear(_) => (first..=last)
                            .map(|g| {
                                let x = points[nd + g];
                                pr.drive_scale(x.x, x.y)
                            })
                            .collect(),
                        _ => Vec::new(),
                    };
                    ops.penalty.moving.push(MovingEdge {
                        points: first..last + 1,
                        component,
                        scale,
                        drive: Drive::new(law),
                    });
                }
            }
        }
        let info = BuildInfo {
            nodes: support.len(),
            dofs: ndof,
            domain_points: nd,
            boundary_points: points.len() - nd,
            min_cover: shapes.min_cover(),
            max_cover: shapes.max_cover(),
            nnz: ops.k.pattern.nnz(),
            shape_seconds,
            assembly_seconds,
        };
        drop(shapes);
        let mut f_permanent = vec![0.0; ndof];
        let mut f_released = vec![0.0; ndof];
        let released = |name: &str| spec.is_released(name);
        // loads: tractions (Eq. 27, boundary term)
        let mut row = ShapeRow::new();
        let mut timed = Vec::new();
        let mut scratch = Vec::new();
        for (bi, bc) in spec.bc.iter().enumerate().filter(|(_, b)| b.is_load()) {
            let target = if bc.table.is_some() {
                scratch.clear();
                scratch.resize(ndof, 0.0);
                &mut scratch
            } else if bc.name.as_deref().is_some_and(released) {
                &mut f_released
            } else {
                &mut f_permanent
            };
            for &(a, b, normal, m, g) in &pieces[bi] {
                for QuadPoint { x, w } in quadrature::edge_points(a, b, m, g) {
                    let tr = match normal {
                        Some(nv) => traction_normal(bc, a, b, x, nv),
                        None => traction_at(bc, a, b, x),
                    };
                    shape_functions(&support, x, &mut row)
                        .map_err(|e| EfgError::coverage(e, spec.d_max, &spec.name))?;
                    for k in 0..row.len() {
                        let i = row.idx[k] as usize;
                        target[2 * i] += w * t * row.phi[k] * tr[0];
                        target[2 * i + 1] += w * t * row.phi[k] * tr[1];
                    }
                }
            }
            if let Some(tb) = &bc.table {
                timed.push(TimedLoad::from_dense(tb.clone(), &scratch));
            }
        }
        // point loads at material points, F += Φᵀ(p) f (Eq. 46)
        for pl in &spec.loads {
            shape_functions(&support, Vec2::from(pl.point), &mut row)
                .map_err(|e| EfgError::coverage(e, spec.d_max, &spec.name))?;
            let target = if pl.table.is_some() {
                scratch.clear();
                scratch.resize(ndof, 0.0);
                &mut scratch
            } else {
                &mut f_permanent
            };
            for k in 0..row.len() {
                let i = row.idx[k] as usize;
                target[2 * i] += row.phi[k] * pl.force[0];
                target[2 * i + 1] += row.phi[k] * pl.force[1];
            }
            if let Some(tb) = &pl.table {
                timed.push(TimedLoad::from_dense(tb.clone(), &scratch));
            }
        }
        // body force ρ g (Eq. 27, domain term)
        if spec.self_weight && gravity != [0.0, 0.0] && el.density > 0.0 {
            let target = if released("gravity") {
                &mut f_released
            } else {
                &mut f_permanent
            };
            for (i, s) in ops.phi_integral.iter().enumerate() {
                target[2 * i] += el.density * gravity[0] * s;
                target[2 * i + 1] += el.density * gravity[1] * s;
            }
        }
        let faces = match &mesh {
            Some(m) => FaceContact::build(&m.cracks, &spec.cracks, &support, el.e, t)
                .map_err(|e| EfgError::coverage(e, spec.d_max, &spec.name))?,
            None => FaceContact::default(),
        };
        Ok(EfgBody {
            name: spec.name.clone(),
            grid: if mesh.is_some() { [0, 0] } else { spec.nodes },
            mesh,
            xs,
            ys,
            origin,
            size,
            support,
            material,
            d_max: spec.d_max,
            ops,
            f_permanent,
            f_released,
            f_point: vec![0.0; ndof],
            timed,
            load_work: 0.0,
            contact_force: Vec2::ZERO,
            refine_work: Default::default(),
            refine_pending: false,
            refine_rows: None,
            motion_work: 0.0,
            state: State::zeros(ndof),
            time: 0.0,
            step: 0,
            params: NewmarkParams {
                dt: 0.0,
                gamma: spec.newmark[0],
                beta: spec.newmark[1],
            },
            newmark: None,
            timoshenko,
            info,
            increments: vec![[0, 0]; spec.cracks.len()],
            spec: spec.clone(),
            gravity,
            fracture_energy: 0.0,
            faces,
        })
    }

    /// The cracks of the body (none for a body without).
    pub fn cracks(&self) -> &[super::polygon::CrackNodes] {
        self.mesh.as_ref().map_or(&[], |m| &m.cracks)
    }

    /// Number of nodes.
    pub fn n_nodes(&self) -> usize {
        self.support.len()
    }
    /// Number of unknowns, `2 · n_nodes` (interleaved x, y).
    pub fn n_dofs(&self) -> usize {
        2 * self.support.len()
    }
    /// Reference position of node `i`.
    pub fn node(&self, i: usize) -> Vec2 {
        let n = &self.support.node[i];
        Vec2::new(n[0], n[1])
    }

    /// Static solve `K̄ U = F` with the permanent and released loads, the
    /// penalty load `F^α` and the accumulated point loads; the state
    /// becomes (U, 0, 0).
    pub fn solve_static(&mut self) -> Result<(), EfgError> {
        let mut f: Vec<f64> = (0..self.n_dofs())
            .map(|i| self.f_permanent[i] + self.f_released[i] + self.f_point[i])
            .collect();
        for l in &self.timed {
            l.add_to(&mut f, self.time);
        }
        self.ops.penalty.add_load(&mut f, When::Now);
        let mut ch = Cholesky::factor(&self.ops.kbar())?;
        ch.solve_in_place(&mut f);
        // the faces of the cracks in contact, from the unloaded state
        self.faces.refactored();
        self.faces.shear.iter_mut().for_each(|s| *s = 0.0);
        let zero = vec![0.0; f.len()];
        self.faces
            .solve(&mut |x| ch.solve_in_place(x), &zero, &mut f, Law::End, 1.0)
            .map_err(|e| self.face_error(e))?;
        self.state.u = f;
        self.state.v.iter_mut().for_each(|x| *x = 0.0);
        self.state.a.iter_mut().for_each(|x| *x = 0.0);
        Ok(())
    }

    /// Prepare time stepping with step `dt` and the body's γ, β: factor
    /// `α₁M + α₄C + K̄` once and compute the initial acceleration from the
    /// equation of motion under the permanent loads (released loads off).
    pub fn start_dynamic(&mut self, dt: f64) -> Result<(), EfgError> {
        crate::continuum::newmark::check_dynamic(dt, self.material.density, &self.name)
            .map_err(EfgError::Invalid)?;
        self.params.dt = dt;
        let (m, c) = self.mass_damping();
        let mut f: Vec<f64> = (0..self.n_dofs())
            .map(|i| self.f_permanent[i] + self.f_point[i])
            .collect();
        for l in &self.timed {
            l.add_to(&mut f, self.step as f64 * dt);
        }
        self.ops.penalty.add_load(&mut f, When::Now);
        let kbar = self.ops.kbar();
        crate::continuum::newmark::consistent_acceleration(
            &m,
            c.as_ref(),
            &kbar,
            &mut self.state,
            &f,
            None,
        )?;
        let nm = Newmark::new(m, c, kbar, self.params)?;
        self.newmark = Some(nm);
        self.refine_rows = None;
        self.faces.refactored();
        Ok(())
    }

    /// Go on from the present state with steps of `dt`, `scale.0` of them
    /// per `scale.1` present steps: `α₁M + α₄C + K̄` factored for `dt`, the state (its
    /// acceleration the last step's) and the time kept, the step count
    /// scaled so that the time is still `step · dt`.
    pub fn retime(&mut self, dt: f64, scale: (usize, usize)) -> Result<(), EfgError> {
        crate::continuum::newmark::check_dynamic(dt, self.material.density, &self.name)
            .map_err(EfgError::Invalid)?;
        self.newmark.as_ref().ok_or(EfgError::NotStarted)?;
        self.params.dt = dt;
        self.step = crate::continuum::rescaled_step(self.step, scale).ok_or_else(|| {
            EfgError::Invalid(format!(
                "body `{}`: step {} is not a whole number of steps of {dt:e} s",
                self.name, self.step
            ))
        })?;
        let (m, c) = self.mass_damping();
        self.newmark = Some(Newmark::new(m, c, self.ops.kbar(), self.params)?);
        self.refine_rows = None;
        Ok(())
    }

    /// The mass matrix and the damping matrix (if any) of the body (E9).
    fn mass_damping(&self) -> (crate::sparse::SymCsc, Option<crate::sparse::SymCsc>) {
        let m = self.ops.gram.scaled(self.material.density);
        let c = (self.material.damping > 0.0).then(|| self.ops.gram.scaled(self.material.damping));
        (m, c)
    }

    /// The integrator, once [`EfgBody::start_dynamic`] was called.
    pub fn newmark(&self) -> Option<&Newmark> {
        self.newmark.as_ref()
    }

    /// Mutable access to the integrator (between `predict` and `commit`).
    pub fn newmark_mut(&mut self) -> Option<&mut Newmark> {
        self.newmark.as_mut()
    }

    /// One Newmark step with the permanent loads plus the point loads
    /// accumulated since the last step (then cleared).
    pub fn advance(&mut self) -> Result<(), EfgError> {
        self.predict()?;
        self.commit()
    }

    /// First half of [`advance`](Self::advance): solve the step under the
    /// permanent loads, the accumulated point loads and the prescribed edge
    /// motion at `t + Δt`; the integrator holds the solution until
    /// [`commit`](Self::commit) (the coupling adds implicit contact forces
    /// in between).
    pub fn predict(&mut self) -> Result<&mut Newmark, EfgError> {
        let nm = self.newmark.as_mut().ok_or(EfgError::NotStarted)?;
        for (p, f) in self.f_point.iter_mut().zip(&self.f_permanent) {
            *p += f;
        }
        let (step, dt) = (self.step, self.params.dt);
        let t1 = (step + 1) as f64 * dt;
        for l in &self.timed {
            l.add_to(&mut self.f_point, t1);
        }
        // the drives decide their positions at t + Δt from the state at t
        let pen = &mut self.ops.penalty;
        for k in 0..pen.moving.len() {
            let e = &pen.moving[k];
            let measured = match e.drive.measure() {
                Some(Measure::Contacts) => self.contact_force.to_array()[e.component],
                _ => pen.edge_force(e, &self.state.u, When::Now),
            };
            pen.moving[k].drive.decide(step, dt, measured);
        }
        let refine = !self.ops.penalty.moving.is_empty();
        if refine {
            self.refine_work[0].clone_from(&self.f_point);
        }
        // penalty load with the prescribed values at t + Δt (E4)
        self.ops.penalty.add_load(&mut self.f_point, When::Next);
        nm.predict(&self.state, &self.f_point);
        if refine {
            self.refine_residual()?;
        }
        self.newmark.as_mut().ok_or(EfgError::NotStarted)
    }

    /// Whether the predicted `U₊` waits for its refinement's solve
    /// ([`add_point_forces`](Self::add_point_forces) or
    /// [`commit`](Self::commit) does it).
    pub fn refinement_pending(&self) -> bool {
        self.refine_pending
    }

    /// After [`predict`](Self::predict): `U₊ += A⁻¹ (Φᵀ f + r)`, the
    /// generalised forces `f[k]` on the functional pairs `rows[2k]`,
    /// `rows[2k + 1]` and the pending refinement residual
    /// `r` in one solve (the coupling's implicit contact forces).
    pub fn add_point_forces(
        &mut self,
        rows: &[Vec<(usize, f64)>],
        f: &[Vec2],
    ) -> Result<(), EfgError> {
        let nm = self.newmark.as_mut().ok_or(EfgError::NotStarted)?;
        let r: &[f64] = if self.refine_pending {
            &self.refine_work[0]
        } else {
            &[]
        };
        nm.add_point_forces(rows, f, r);
        self.refine_pending = false;
        Ok(())
    }

    /// One step of iterative refinement of the predicted `U₊`, for bodies
    /// with moving edges: the residual of the equation of motion at
    /// `t + Δt`, `r = F − M Ü₊ − C U̇₊ − K U₊ + Σ_g Φ_gᵀ W_g (ū_g − u(x_g))`
    /// (`Ü₊`, `U̇₊` Newmark's rates of `U₊`, the penalty term from the
    /// springs' gap), then `U₊ += A⁻¹ r`. Why: on a moving edge's penalty
    /// rows U ≈ d(t) and A ≈ α w; the rounding of the stored K̄ and of its
    /// factor acts as a fixed spurious stiffness times d, a force that grows
    /// with d and does work ∝ d² that no energy term holds (a steel footing
    /// driven 0.2 m with α = 10⁵E: 5·10⁻⁶ of the work; refined: 4·10⁻⁸). The
    /// gap-form residual has no such term. Cost: one more solve per step.
    fn refine_residual(&mut self) -> Result<(), EfgError> {
        let nm = self.newmark.as_mut().ok_or(EfgError::NotStarted)?;
        let s = &self.state;
        let pen = &self.ops.penalty;
        // the residual matters on the penalty rows only (elsewhere it is
        // the round-off of ordinary terms): products on those rows
        let sel = self.refine_rows.get_or_insert_with(|| {
            let mut dofs: Vec<usize> = (0..pen.len())
                .flat_map(|g| pen.row(g))
                .flat_map(|(j, _)| [2 * j as usize, 2 * j as usize + 1])
                .collect();
            dofs.sort_unstable();
            dofs.dedup();
            let mats: Vec<&SymCsc> = [Some(&nm.mass), nm.damping.as_ref(), Some(&self.ops.k)]
                .into_iter()
                .flatten()
                .collect();
            RowSelection::new(&mats, dofs)
        });
        let [r, u1, acc, vel, tmp] = &mut self.refine_work;
        u1.clear();
        u1.extend_from_slice(nm.solution());
        // r = F − M Ü₊ − C U̇₊ − K U₊ + springs on those rows (r holds F
        // without F^α on entry)
        tmp.clear();
        tmp.resize(r.len(), 0.0);
        for &i in &sel.rows {
            tmp[i] = r[i];
        }
        std::mem::swap(r, tmp);
        let damped = nm.damping.is_some();
        acc.clear();
        vel.clear();
        tmp.clear();
        for (i, u) in u1.iter().enumerate() {
            let (v, a) = nm.rates(s.u[i], s.v[i], s.a[i], *u);
            acc.push(-a);
            if damped {
                vel.push(-v);
            }
            tmp.push(-u);
        }
        if damped {
            sel.mul_add(&[acc, vel, tmp], r);
        } else {
            sel.mul_add(&[acc, tmp], r);
        }
        pen.add_spring_force(u1, When::Next, r);
        self.refine_pending = true;
        Ok(())
    }

    /// Second half of [`advance`](Self::advance): accept the solution,
    /// clear the point loads, advance the clock.
    pub fn commit(&mut self) -> Result<(), EfgError> {
        let nm = self.newmark.as_mut().ok_or(EfgError::NotStarted)?;
        if self.refine_pending {
            // the refinement not folded into a contact solve
            let r = &mut self.refine_work[0];
            nm.solve_in_place(r);
            for (u, d) in nm.solution_mut().iter_mut().zip(r.iter()) {
                *u += d;
            }
            self.refine_pending = false;
        }
        // the crack faces in contact over the step, with all other forces
        // of the step in U₊: their mean force as an impulse
        let x = 1.0 / self.params.gamma;
        if !self.faces.is_empty() {
            let mut u1 = nm.solution().to_vec();
            let r = self.faces.solve(
                &mut |x| nm.solve_in_place(x),
                &self.state.u,
                &mut u1,
                Law::Mean,
                x,
            );
            nm.solution_mut().copy_from_slice(&u1);
            if let Err(e) = r {
                return Err(self.face_error(e));
            }
        }
        // work of the moving edges over the step, trapezoidal in time
        let (pen, step, dt) = (&self.ops.penalty, self.step, self.params.dt);
        let (t0, t1) = (step as f64 * dt, (step + 1) as f64 * dt);
        let mut work = pen.half_step_work(&self.state.u, When::Now);
        let loads0 = TimedLoad::half_sum(&self.timed, &self.state.u, t0, t1);
        nm.commit(&mut self.state);
        if self.faces.needs_mass() {
            let mut mf = nm.factor().factor_like(&nm.mass)?;
            self.faces
                .mass_columns(&mut |x| mf.solve_in_place(x), self.state.a.len());
        }
        self.faces.impulse_acceleration(&mut self.state.a);
        work += pen.half_step_work(&self.state.u, When::Next);
        self.motion_work += work;
        if !self.timed.is_empty() {
            self.load_work += TimedLoad::half_sum(&self.timed, &self.state.u, t0, t1) - loads0;
        }
        for e in &mut self.ops.penalty.moving {
            e.drive.advance();
        }
        self.f_point.iter_mut().for_each(|x| *x = 0.0);
        self.step += 1;
        self.time = self.step as f64 * self.params.dt;
        Ok(())
    }

    fn face_error(&self, source: super::face_contact::Unsettled) -> EfgError {
        EfgError::FaceContact {
            body: self.name.clone(),
            source,
        }
    }

    /// What changes while the body steps ([`BodyState`]): `U`, `U̇`, `Ü`,
    /// clock, pending point loads, work of the moving edges. Call between
    /// steps (never between [`predict`](Self::predict) and
    /// [`commit`](Self::commit)).
    pub fn save_state(&self) -> BodyState {
        BodyState {
            name: self.name.clone(),
            state: self.state.clone(),
            step: self.step,
            time: self.time,
            f_point: self.f_point.clone(),
            motion_work: self.motion_work,
            drives: self.drives().map(|(_, d)| *d).collect(),
            load_work: self.load_work,
            reactions: Vec::new(),
            boundary: None,
            cracks: (!self.spec.cracks.is_empty()).then(|| CrackState {
                cracks: self.cracks().iter().map(|c| c.crack.clone()).collect(),
                increments: self.increments.clone(),
                fracture_energy: self.fracture_energy,
                face_shear: self.faces.shear.clone(),
            }),
        }
    }

    /// Restore a [`save_state`](Self::save_state) of a body built from the
    /// same parameters (name and DOFs checked). The operators, the factor
    /// and the prescribed motion (a function of the step) are the build's.
    pub fn restore_state(&mut self, s: &BodyState) -> Result<(), StateError> {
        if let Some(c) = &s.cracks {
            self.regrow(c)?;
        }
        s.check(&self.name, self.n_dofs(), 0)?;
        s.check_drives(&self.name, Some(self.ops.penalty.moving.len()))?;
        self.state.clone_from(&s.state);
        if let Some(c) = &s.cracks {
            self.faces.restore(&self.state.u, &c.face_shear);
        }
        for (e, d) in self.ops.penalty.moving.iter_mut().zip(&s.drives) {
            e.drive.state = *d;
        }
        self.load_work = s.load_work;
        self.step = s.step;
        self.time = s.time;
        self.f_point.clone_from(&s.f_point);
        self.motion_work = s.motion_work;
        self.refine_pending = false;
        Ok(())
    }

    /// Rebuild the body with the grown cracks of a saved state (unless
    /// they are the body's), its integrator restarted if it was.
    fn regrow(&mut self, c: &CrackState) -> Result<(), StateError> {
        let now: Vec<&Crack> = self.cracks().iter().map(|k| &k.crack).collect();
        if c.cracks.len() != self.spec.cracks.len() {
            return Err(StateError::new(format!(
                "body `{}`: {} saved cracks, the body has {}",
                self.name,
                c.cracks.len(),
                self.spec.cracks.len()
            )));
        }
        if c.cracks.iter().ne(now) {
            let mut spec = self.spec.clone();
            for (k, saved) in spec.cracks.iter_mut().zip(&c.cracks) {
                k.crack = saved.clone();
            }
            let bad = |e: EfgError| StateError::new(format!("body `{}`: {e}", self.name));
            let mut new = EfgBody::new(&spec, self.gravity).map_err(bad)?;
            if let Some(dt) = self.newmark().map(|_| self.params.dt) {
                new.start_dynamic(dt).map_err(bad)?;
            }
            *self = new;
        }
        if c.face_shear.len() != self.faces.shear.len() {
            return Err(StateError::new(format!(
                "body `{}`: {} saved pairs of crack faces, the body has {}",
                self.name,
                c.face_shear.len(),
                self.faces.shear.len()
            )));
        }
        self.increments.clone_from(&c.increments);
        self.fracture_energy = c.fracture_energy;
        Ok(())
    }

    /// The drives (moving edge components) with their components (0: x,
    /// 1: y), in build order.
    pub fn drives(&self) -> impl Iterator<Item = (usize, &DriveState)> {
        self.ops
            .penalty
            .moving
            .iter()
            .map(|e| (e.component, &e.drive.state))
    }

    /// Shape functions (and derivatives) of this body at `p`: the row
    /// `φ_J(p)` used for sampling, boundary velocity and point loads (E7).
    pub fn shape_row(&self, p: Vec2, row: &mut ShapeRow) -> Result<(), EfgError> {
        shape_functions(&self.support, p, row)
            .map_err(|e| EfgError::coverage(e, self.d_max, &self.name))
    }

    /// Add the point load `f` at `p` to the next step's force:
    /// `F += Φᵀ(p) f` (Eq. 46, same φ_J as the sampling, E7).
    pub fn add_point_load_row(&mut self, row: &ShapeRow, f: Vec2) {
        for (&i, &phi) in row.idx.iter().zip(&row.phi) {
            self.f_point[2 * i as usize] += phi * f.x;
            self.f_point[2 * i as usize + 1] += phi * f.y;
        }
    }

    /// [`EfgBody::add_point_load_row`] at a point.
    pub fn add_point_load(&mut self, p: Vec2, f: Vec2) -> Result<(), EfgError> {
        let mut row = ShapeRow::new();
        self.shape_row(p, &mut row)?;
        self.add_point_load_row(&row, f);
        Ok(())
    }

    /// True fields from a precomputed shape row.
    pub fn sample_row(&self, row: &ShapeRow) -> Sample {
        let (u, v) = (&self.state.u, &self.state.v);
        let mut s = Sample::default();
        let mut e = [0.0; 3];
        for k in 0..row.len() {
            let i = row.idx[k] as usize;
            let (ux, uy) = (u[2 * i], u[2 * i + 1]);
            s.u.x += row.phi[k] * ux;
            s.u.y += row.phi[k] * uy;
            s.v.x += row.phi[k] * v[2 * i];
            s.v.y += row.phi[k] * v[2 * i + 1];
            e[0] += row.dx[k] * ux;
            e[1] += row.dy[k] * uy;
            e[2] += row.dy[k] * ux + row.dx[k] * uy;
        }
        s.strain = e;
        s.stress = self.material.stress(e);
        s
    }

    /// True displacement, velocity, strain and stress at `p`.
    pub fn sample(&self, p: Vec2) -> Result<Sample, EfgError> {
        let mut row = ShapeRow::new();
        self.shape_row(p, &mut row)?;
        Ok(self.sample_row(&row))
    }

    /// Kinetic energy `½ U̇ᵀ M U̇`.
    pub fn kinetic_energy(&self) -> f64 {
        0.5 * self.material.density * self.ops.gram.quad_form(&self.state.v)
    }
    /// Elastic strain energy `½ Uᵀ K U` (K without the penalty).
    pub fn elastic_energy(&self) -> f64 {
        0.5 * self.ops.k.quad_form(&self.state.u)
    }
    /// Energy of the penalty springs, from their gap to the prescribed
    /// displacement at the present time (moving edges included):
    /// `½ Σ_g (u(x_g) − ū_g)ᵀ W_g (u(x_g) − ū_g)` (E4, [`super::penalty`]),
    /// and of the crack faces in contact ([`FaceContact::energy`]).
    pub fn penalty_energy(&self) -> f64 {
        self.ops.penalty.energy(&self.state.u, When::Now) + self.faces.energy()
    }
    /// Strain energy including the penalty springs:
    /// [`elastic_energy`](Self::elastic_energy) +
    /// [`penalty_energy`](Self::penalty_energy). With ū = 0 this is
    /// `½ Uᵀ K̄ U`.
    pub fn strain_energy(&self) -> f64 {
        self.elastic_energy() + self.penalty_energy()
    }

    /// Relative energy-norm error `‖ε − ε_ex‖_E / ‖ε_ex‖_E` against an exact
    /// stress field (strain recovered with `D⁻¹`), integrated with `gauss`²
    /// points on `cells`.
    pub fn energy_error(
        &self,
        exact_stress: impl Fn(Vec2) -> [f64; 3],
        cells: [usize; 2],
        gauss: usize,
    ) -> Result<f64, EfgError> {
        let mut row = ShapeRow::new();
        energy_error_of(
            &self.material,
            self.origin,
            self.size,
            cells,
            gauss,
            |p| {
                self.shape_row(p, &mut row)?;
                Ok(self.sample_row(&row))
            },
            exact_stress,
        )
    }

    /// [`energy_error`](Self::energy_error) of a polygon body, integrated
    /// over its triangles with each split into `sub²` (7 points each).
    pub fn energy_error_polygon(
        &self,
        exact_stress: impl Fn(Vec2) -> [f64; 3],
        sub: usize,
    ) -> Result<f64, EfgError> {
        let Some(mesh) = &self.mesh else {
            return Err(EfgError::Invalid(format!(
                "body `{}` is not a polygon body",
                self.name
            )));
        };
        let [d11, d12, _, d33] = self.material.d;
        let det = d11 * d11 - d12 * d12;
        let compl = |s: [f64; 3]| {
            [
                (d11 * s[0] - d12 * s[1]) / det,
                (d11 * s[1] - d12 * s[0]) / det,
                s[2] / d33,
            ]
        };
        let (mut num, mut den) = (0.0, 0.0);
        let mut row = ShapeRow::new();
        for q in mesh.domain_points(sub) {
            self.shape_row(q.x, &mut row)?;
            let s = self.sample_row(&row);
            let se = exact_stress(q.x);
            let ee = compl(se);
            let mut dn = 0.0;
            let mut dd = 0.0;
            for k in 0..3 {
                dn += (s.stress[k] - se[k]) * (s.strain[k] - ee[k]);
                dd += se[k] * ee[k];
            }
            num += q.w * dn;
            den += q.w * dd;
        }
        Ok((num / den).sqrt())
    }

    /// The points of the body's frames: the nodes, and for a polygon body
    /// the boundary vertices that are not nodes after them (the corners
    /// of its triangles, [`PolygonMesh::points`]).
    pub fn frame_points(&self) -> Vec<Vec2> {
        match &self.mesh {
            Some(m) => m.points.clone(),
            None => (0..self.n_nodes()).map(|i| self.node(i)).collect(),
        }
    }

    /// Shape functions at every [frame point](Self::frame_points) (for
    /// nodal output).
    pub fn nodal_shapes(&self) -> Result<PointShapes, EfgError> {
        assemble::point_shapes(&self.support, &self.frame_points())
            .map_err(|e| EfgError::coverage(e, self.d_max, &self.name))
    }
}

/// The polygon a rectangle with cracks is meshed as: its four corners
/// (counter-clockwise from the lower left), the four sides named `bottom`,
/// `right`, `top`, `left`, at the spacing `min(width/(nx − 1),
/// height/(ny − 1))` of its node grid.
pub fn rectangle_polygon(
    rectangle: &crate::continuum::Rectangle,
    nodes: [usize; 2],
) -> Result<crate::continuum::PolygonShape, String> {
    let [nx, ny] = nodes;
    if nx < 2 || ny < 2 {
        return Err("the node grid needs at least 2 × 2 nodes".into());
    }
    let o = Vec2::from(rectangle.origin);
    let s = Vec2::from(rectangle.size);
    let corners = vec![
        o,
        Vec2::new(o.x + s.x, o.y),
        o + s,
        Vec2::new(o.x, o.y + s.y),
    ];
    let edges = Edge::ALL
        .iter()
        .enumerate()
        .map(|(i, e)| (e.name().to_string(), vec![(0, i)]))
        .collect();
    let domain =
        crate::geom::polygon::Domain::new(corners, vec![], edges).map_err(|e| e.to_string())?;
    Ok(crate::continuum::PolygonShape {
        domain,
        spacing: (s.x / (nx - 1) as f64).min(s.y / (ny - 1) as f64),
        refine: Vec::new(),
    })
}
