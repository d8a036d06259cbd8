//! Contact of closing crack faces: the faces may not pass through each
//! other and carry compression and Coulomb friction when they touch.
//!
//! **Where.** At every station of a crack with a pair of face nodes (all
//! but the tips), a *face point*: the jump `Δ = u(x_L) − u(x_R)` of the
//! displacement between its left and right face node (each interpolated
//! with its own face's shape functions, which the visibility criterion
//! keeps apart), its normal gap `g = n·Δ` (`n` the left normal of the
//! crack: `g < 0` is interpenetration) and its slip `s = t·Δ`
//! (`t = −n⊥`, along the crack). The jump is a pair of linear functionals
//! of the nodal parameters, `Δ = Ψ U`, `Ψ = Φ(x_L) − Φ(x_R)`, and a force
//! `f` on the pair loads the left face with `f` and the right with `−f`
//! (`F += Ψᵀ f`).
//!
//! **Law (penalty).** A closed point (`g < 0`) pushes the faces apart
//! with `f_n = −k_n g` and resists slip with an elastic–Coulomb spring:
//! `f_t = f_t,old − k_t (s − s_old)`, capped at `μ f_n`; an open point
//! carries nothing and forgets its shear. `k_n = k_t = κ ℓ t` with `ℓ`
//! the station's share of the crack length, `t` the thickness and `κ`
//! (stress per length) the face stiffness. A penalty rather than
//! Lagrange multipliers because the rows `Ψ` of neighbouring stations
//! are nearly dependent (EFG shape functions are smooth over several
//! stations), so the multipliers' system `S λ = −g` is nearly singular;
//! the penalty adds `1/κ` to its diagonal. The default
//! `κ = 100 E / h_c` (`h_c` the crack's node spacing) lets faces overlap
//! by `p h_c / (100 E)` under a pressure `p` — 10⁻⁵ `h_c` at a strain
//! of 10⁻³ — while the contact system stays well conditioned.
//!
//! **Solve (implicit, in the body's own step).** After a static solve or
//! the Newmark step's solution `U₊` (with the coupling's forces), the
//! jumps are `Δ = Δ_free + S f(Δ)`, `S = Ψ A⁻¹ Ψᵀ` with `A` the factored
//! matrix (`K̄`, or `α₁M + α₄C + K̄`). `A⁻¹Ψᵀ` is computed once per factor
//! (two solves per face point, only once some face closes). That small
//! system is solved by semi-smooth Newton, each step over the active
//! points only, exact once the points' regimes settle; then
//! `U₊ += A⁻¹Ψᵀ f`. In a Newmark step `f` is the faces' mean force over
//! the step, so that the step conserves energy with them
//! ([`FaceContact::solve`]).

use super::polygon::CrackNodes;
use super::shape::{CoverageError, ShapeRow, shape_functions};
use super::support::Support;
use crate::continuum::CrackShape;
use crate::geom::Vec2;
use crate::sparse::gauss_solve;

/// Newton iterations at most (the regimes settle in a few).
const MAX_ITER: usize = 60;
/// The residual, relative to the free jumps, at which the solve has
/// converged (round-off of the products `S f`).
const TOL: f64 = 1e-13;
/// The residual at which a solve that still changes regimes at
/// [`MAX_ITER`] is accepted.
const ACCEPT: f64 = 1e-9;

/// One face point ([module docs](self)).
#[derive(Debug, Clone)]
pub struct FacePoint {
    /// Reference position on the crack.
    pub x: Vec2,
    /// Unit normal to the left of the crack.
    pub n: Vec2,
    /// Normal and tangential stiffness `κ ℓ t`.
    pub k: f64,
    /// Friction coefficient μ.
    pub mu: f64,
    /// Crack the point is on.
    pub crack: usize,
    /// Where its left and right face are sampled: its station's face
    /// nodes, off the crack on each side.
    pub at: [Vec2; 2],
    /// Its station's distance along the crack from the crack's first
    /// point, and the stretch of crack it stands for (from half-way to
    /// each neighbouring station, or to a tip next to it).
    pub arc: f64,
    /// That stretch, `[from, to]` along the crack.
    pub span: [f64; 2],
}

/// What one point does over a step ending at the jump `Δ`: the force it
/// puts on the left face (`f`, with its Jacobian `∂f/∂Δ`, row-major), the
/// force it holds at the end (`end`), its regime (0 inactive, 1 stick,
/// 2 slip, 3 released: closed at the start, open at the end) and whether
/// `f` is affine in `Δ` near this `Δ` (a Newton step is then exact).
#[derive(Debug, Clone, Copy, PartialEq)]
struct Eval {
    f: Vec2,
    jac: [f64; 4],
    end: Vec2,
    regime: u8,
    affine: bool,
}

/// How the force a point puts on the faces over a step follows from the
/// jumps: at the end of the step (a static solve), or the step's mean
/// (a Newmark step, [`FaceContact::solve`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Law {
    /// The force of the jump at the end of the solve.
    End,
    /// The mean force over a Newmark step from the jump at its start.
    Mean,
}

impl FacePoint {
    /// Tangent along the crack, `(n, t)` right-handed.
    fn t(&self) -> Vec2 {
        -self.n.perp()
    }

    /// The normal force over a step from the gap `g0` to `g1` that does
    /// exactly the work the penalty's energy `V(g) = ½ k min(g, 0)²`
    /// releases, `f̄ = −(V(g₁) − V(g₀))/(g₁ − g₀)` (the discrete gradient),
    /// and `∂f̄/∂g₁`. Closed at both ends it is the trapezoid
    /// `−k (g₀ + g₁)/2` (the average-acceleration step's own mean); when
    /// the point closes or opens within the step it is what the spring
    /// takes or gives back, where the trapezoid of the end forces
    /// (`½ f(g₁)`, `½ f(g₀)`) would book `½ k |g₁ g₀|` too much or too
    /// little. `f̄` is C¹ in `g₁` and decreasing.
    fn mean_normal(&self, g0: f64, g1: f64) -> (f64, f64) {
        let k = self.k;
        match (g0 < 0.0, g1 < 0.0) {
            (true, true) => (-0.5 * k * (g0 + g1), -0.5 * k),
            (true, false) => {
                let d = g1 - g0;
                (0.5 * k * g0 * g0 / d, -0.5 * k * g0 * g0 / (d * d))
            }
            (false, true) => {
                let d = g1 - g0;
                (
                    -0.5 * k * g1 * g1 / d,
                    -0.5 * k * g1 * (g1 - 2.0 * g0) / (d * d),
                )
            }
            (false, false) => (0.0, 0.0),
        }
    }

    /// The law over a step from the jump `d0` (shear `shear_old`) to the
    /// jump `d`. At the end, a closed point (`g < 0`) holds `f_n = −k g`
    /// and the elastic–Coulomb shear `f_t = f_t,old − k (s − s_old)`
    /// capped at `μ f_n`; an open one nothing (its shear is forgotten).
    /// [`Law::End`] puts that end force on the faces; [`Law::Mean`] the
    /// step's mean: the normal [`mean_normal`](Self::mean_normal) `f̄_n`,
    /// the shear `½ (f_t,old + f_t)` while the point ends closed (exact for
    /// a sticking spring, within `μ f̄_n`); a point that opens in the step
    /// carries `½ f_t,old |g₀|/(g − g₀)`, continuous in `Δ` and within
    /// `μ f̄_n` as well.
    fn eval(&self, d: Vec2, d0: Vec2, shear_old: f64, law: Law) -> Eval {
        let (n, t, k) = (self.n, self.t(), self.k);
        let (g, g0) = (n.dot(d), n.dot(d0));
        let (mut end, mut ft, mut dft, mut regime) = (Vec2::ZERO, 0.0, Vec2::ZERO, 0);
        let fnorm = -k * g.min(0.0);
        if g < 0.0 {
            let trial = shear_old - k * (t.dot(d) - t.dot(d0));
            let cap = self.mu * fnorm;
            // ∂f_t/∂Δ = −k t (stick) or σ μ (−k n) (slip)
            (ft, dft, regime) = if trial.abs() <= cap {
                (trial, t * -k, 1)
            } else {
                let sg = trial.signum();
                (sg * cap, n * (-k * self.mu * sg), 2)
            };
            end = n * fnorm + t * ft;
        }
        let (f, dfn, affine) = match law {
            Law::End => (end, n * -k, true),
            Law::Mean => {
                let (fbar, dfbar) = self.mean_normal(g0, g);
                if g0 < 0.0 && g >= 0.0 {
                    regime = 3;
                }
                if g < 0.0 {
                    (ft, dft) = (0.5 * (shear_old + ft), dft * 0.5);
                } else if g0 < 0.0 {
                    // opening: the start's half shear fading as the mean
                    // normal force does (continuous at g = 0, within μ f̄_n)
                    let c = -g0 / (g - g0);
                    (ft, dft) = (0.5 * shear_old * c, n * (-0.5 * shear_old * c / (g - g0)));
                }
                (n * fbar + t * ft, n * dfbar, (g0 < 0.0) == (g < 0.0))
            }
        };
        if regime == 0 {
            return Eval {
                f: Vec2::ZERO,
                jac: [0.0; 4],
                end,
                regime,
                affine: true,
            };
        }
        Eval {
            f,
            jac: [
                n.x * dfn.x + t.x * dft.x,
                n.x * dfn.y + t.x * dft.y,
                n.y * dfn.x + t.y * dft.x,
                n.y * dfn.y + t.y * dft.y,
            ],
            end,
            regime,
            affine,
        }
    }
}

/// The face points of a body and what the contact solve keeps.
#[derive(Debug, Clone, Default)]
pub struct FaceContact {
    /// The points, crack after crack, station after station.
    pub points: Vec<FacePoint>,
    /// `Ψ`: per point its `x` and `y` rows `[(DOF, coefficient)]`.
    pub rows: Vec<Vec<(usize, f64)>>,
    /// `A⁻¹Ψᵀ` of the present factor, column after column (empty until a
    /// face first closes).
    z: Vec<f64>,
    /// `S = Ψ A⁻¹ Ψᵀ`, 2m × 2m row-major.
    s: Vec<f64>,
    /// Per point its shear force `f_t` at the present state.
    pub shear: Vec<f64>,
    /// Per point the force on its left face at the present state.
    pub force: Vec<Vec2>,
    /// Per point the force the last solve put on the faces (the end force
    /// of a static solve; `1/γ` × the mean of a Newmark step).
    applied: Vec<Vec2>,
    /// `M⁻¹Ψᵀ`, column after column (empty until a dynamic step first
    /// needs it; the mass matrix does not change with Δt).
    w: Vec<f64>,
}

/// `x += c Σ_k (f_k.x B⁻¹ψ_2k + f_k.y B⁻¹ψ_2k+1)` with the columns
/// `cols` of `B⁻¹Ψᵀ`.
fn add_columns(cols: &[f64], f: &[Vec2], c: f64, x: &mut [f64]) {
    for (j, col) in cols.chunks_exact(x.len()).enumerate() {
        let fj = c * if j % 2 == 0 { f[j / 2].x } else { f[j / 2].y };
        if fj != 0.0 {
            for (xi, zi) in x.iter_mut().zip(col) {
                *xi += fj * zi;
            }
        }
    }
}

/// The contact problem could not be solved.
#[derive(Debug, Clone, thiserror::Error)]
#[error(
    "the contact of the crack faces did not settle after {MAX_ITER} Newton iterations (residual {residual:.2e} of the jumps {scale:.2e})"
)]
pub struct Unsettled {
    /// Norm of the last residual.
    pub residual: f64,
    /// Norm of the jumps.
    pub scale: f64,
}

impl FaceContact {
    /// The face points of `cracks` (meshed from `shapes`) in a body of
    /// Young's modulus `e` and thickness `t`: one per station with two
    /// face nodes, its jump rows from the shape functions at the face
    /// nodes.
    pub fn build(
        cracks: &[CrackNodes],
        shapes: &[CrackShape],
        support: &Support,
        e: f64,
        t: f64,
    ) -> Result<FaceContact, CoverageError> {
        let mut points = Vec::new();
        let mut rows = Vec::new();
        let (mut left, mut right) = (ShapeRow::new(), ShapeRow::new());
        let node = |i: usize| Vec2::new(support.node[i][0], support.node[i][1]);
        for (c, (cn, shape)) in cracks.iter().zip(shapes).enumerate() {
            let st = &cn.stations;
            let h = cn.crack.length() / (st.len() - 1) as f64;
            let kappa = shape.face_stiffness.unwrap_or(100.0 * e / h);
            let mut arc = vec![0.0];
            for w in st.windows(2) {
                arc.push(arc[arc.len() - 1] + (w[1] - w[0]).norm());
            }
            let tip = |k: usize| cn.nodes[k][0] == cn.nodes[k][1];
            for (k, &[l, r]) in cn.nodes.iter().enumerate() {
                if tip(k) {
                    continue;
                }
                {
                    let (prev, next) = (k.saturating_sub(1), (k + 1).min(st.len() - 1));
                    // half-way to a neighbouring station, all the way to a tip
                    let end = |j: usize| {
                        if tip(j) {
                            arc[j]
                        } else {
                            0.5 * (arc[j] + arc[k])
                        }
                    };
                    let span = [end(prev), end(next)];
                    let d = st[next] - st[prev];
                    let at = [node(l), node(r)];
                    shape_functions(support, at[0], &mut left)?;
                    shape_functions(support, at[1], &mut right)?;
                    points.push(FacePoint {
                        x: st[k],
                        n: d.perp() * (1.0 / d.norm()),
                        k: kappa * (span[1] - span[0]) * t,
                        mu: shape.friction,
                        crack: c,
                        at,
                        arc: arc[k],
                        span,
                    });
                    for a in 0..2 {
                        let mut row: Vec<(usize, f64)> = left
                            .idx
                            .iter()
                            .zip(&left.phi)
                            .map(|(&j, &p)| (2 * j as usize + a, p))
                            .chain(
                                right
                                    .idx
                                    .iter()
                                    .zip(&right.phi)
                                    .map(|(&j, &p)| (2 * j as usize + a, -p)),
                            )
                            .collect();
                        row.sort_by_key(|x| x.0);
                        row.dedup_by(|x, y| {
                            let same = x.0 == y.0;
                            if same {
                                y.1 += x.1;
                            }
                            same
                        });
                        rows.push(row);
                    }
                }
            }
        }
        Ok(FaceContact::new(points, rows))
    }

    /// Face points `points` with their jump rows `rows` (two per point).
    pub fn new(points: Vec<FacePoint>, rows: Vec<Vec<(usize, f64)>>) -> Self {
        let m = points.len();
        FaceContact {
            points,
            rows,
            shear: vec![0.0; m],
            force: vec![Vec2::ZERO; m],
            ..Default::default()
        }
    }

    /// No face points (a body without cracks).
    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }

    /// Forget `A⁻¹Ψᵀ` (the factor changed).
    pub fn refactored(&mut self) {
        self.z.clear();
        self.s.clear();
    }

    /// Jumps `Ψ x` of the nodal vector `x`.
    pub fn jumps(&self, x: &[f64]) -> Vec<Vec2> {
        let mut out = Vec::new();
        crate::continuum::newmark::pair_values(&self.rows, x, &mut out);
        out
    }

    /// Contact with the faces at the solution `u1` of a step solved with
    /// `factor`, from the state `u0`: `u1 += A⁻¹Ψᵀ (x f)` with the forces
    /// `f` of `law` ([`Law::End`]: a static solve, from `u0 = 0`, `x = 1`;
    /// [`Law::Mean`]: a Newmark step, `x = 1/γ`). The end forces and shear
    /// are kept. Returns the Newton iterations (0: no face in contact).
    ///
    /// **Why the mean in a Newmark step.** The average-acceleration step
    /// conserves `½U̇ᵀMU̇ + ½UᵀKU` up to the work of the trapezoid of the
    /// loads at its two ends, `½(f₀ + f₁)·ΔΔ`. For the face springs that
    /// trapezoid is their energy change only while a point stays closed: a
    /// point that opens within a step gives back `½ k |g₀| g₁` more than
    /// it held. Faces that slap open and shut, with a penalty stiff against
    /// the step (`Δt √(k/m) ≫ 1`: the closed step rings at the Nyquist
    /// frequency), pump energy into the body at every opening until it
    /// blows up. So the step carries the faces' mean force `f̄` over the
    /// step, the discrete gradient of their energy, as an impulse:
    /// `U̇₊ = U̇ + Δt/2 (Ü + Ü₊) + Δt M⁻¹Ψᵀf̄`, `U₊ = U + Δt U̇ + Δt²/4
    /// (Ü + Ü₊) + Δt²/2 M⁻¹Ψᵀf̄` with `Ü` the acceleration of the other
    /// loads: the solve adds `2f̄` as an end load and
    /// [`impulse_acceleration`](Self::impulse_acceleration) takes its
    /// acceleration back out of `Ü₊`. The faces then do exactly the work
    /// `f̄·ΔΔ = −ΔV`: the step conserves energy with the faces' as with
    /// any spring (for γ ≠ ½ the velocity still receives `Δt M⁻¹Ψᵀf̄`).
    pub fn solve(
        &mut self,
        solve: &mut dyn FnMut(&mut [f64]),
        u0: &[f64],
        u1: &mut [f64],
        law: Law,
        x: f64,
    ) -> Result<usize, Unsettled> {
        let free = self.jumps(u1);
        let old = self.jumps(u0);
        let closed = |d: &[Vec2]| d.iter().zip(&self.points).any(|(d, p)| p.n.dot(*d) < 0.0);
        if !closed(&free) && (law == Law::End || !closed(&old)) {
            self.force.iter_mut().for_each(|f| *f = Vec2::ZERO);
            self.shear.iter_mut().for_each(|f| *f = 0.0);
            self.applied.clear();
            return Ok(0);
        }
        if self.z.is_empty() {
            self.compliance(solve, u1.len());
        }
        let (iters, e) = self.newton(&free, &old, law, x)?;
        let f: Vec<Vec2> = e.iter().map(|e| e.f).collect();
        add_columns(&self.z, &f, 1.0, u1);
        for (k, p) in self.points.iter().enumerate() {
            self.shear[k] = e[k].end.dot(p.t());
            self.force[k] = e[k].end;
        }
        self.applied = f;
        Ok(iters)
    }

    /// Whether [`mass_columns`](Self::mass_columns) must be called before
    /// [`impulse_acceleration`](Self::impulse_acceleration).
    pub fn needs_mass(&self) -> bool {
        !self.applied.is_empty() && self.w.is_empty()
    }

    /// `M⁻¹Ψᵀ` with `solve_mass` solving with `M` (2 solves per point),
    /// once per body: the mass matrix does not change with Δt.
    pub fn mass_columns(&mut self, solve_mass: &mut dyn FnMut(&mut [f64]), n: usize) {
        self.w = self.columns(solve_mass, n);
    }

    /// Subtract from `a` the acceleration `M⁻¹Ψᵀ f` of the forces `f` the
    /// last [`Law::Mean`] solve put on the faces: their impulse is in the
    /// velocity, not in the acceleration the next step starts from
    /// ([`solve`](Self::solve)).
    pub fn impulse_acceleration(&self, a: &mut [f64]) {
        if self.applied.is_empty() {
            return;
        }
        add_columns(&self.w, &self.applied, -1.0, a);
    }

    /// The end forces and shear of the state `u` after a restart (the
    /// shear restored): what [`energy`](Self::energy) and the interaction
    /// integral read.
    pub fn restore(&mut self, u: &[f64], shear: &[f64]) {
        self.shear.clone_from_slice(shear);
        let d = self.jumps(u);
        for (k, p) in self.points.iter().enumerate() {
            let g = p.n.dot(d[k]);
            self.force[k] = if g < 0.0 {
                p.n * (-p.k * g) + p.t() * shear[k]
            } else {
                Vec2::ZERO
            };
        }
    }

    /// `B⁻¹Ψᵀ` column after column for the solve `solve` with `B`.
    fn columns(&self, solve: &mut dyn FnMut(&mut [f64]), n: usize) -> Vec<f64> {
        let mut z = vec![0.0; self.rows.len() * n];
        for (col, row) in z.chunks_exact_mut(n).zip(&self.rows) {
            for &(i, c) in row {
                col[i] += c;
            }
            solve(col);
        }
        z
    }

    /// `A⁻¹Ψᵀ` and `S` for the factor (2m solves).
    fn compliance(&mut self, solve: &mut dyn FnMut(&mut [f64]), n: usize) {
        let m2 = self.rows.len();
        self.z = self.columns(solve, n);
        self.s.clear();
        self.s.resize(m2 * m2, 0.0);
        for (c, col) in self.z.chunks_exact(n).enumerate() {
            for (r, row) in self.rows.iter().enumerate() {
                self.s[r * m2 + c] = crate::continuum::newmark::functional(row, col);
            }
        }
    }

    /// `S f` for forces `f` per point.
    fn s_times(&self, f: &[Vec2]) -> Vec<Vec2> {
        let m2 = 2 * f.len();
        (0..f.len())
            .map(|k| {
                let mut y = [0.0; 2];
                for (a, ya) in y.iter_mut().enumerate() {
                    let row = &self.s[(2 * k + a) * m2..(2 * k + a + 1) * m2];
                    *ya = f
                        .iter()
                        .enumerate()
                        .map(|(l, fl)| row[2 * l] * fl.x + row[2 * l + 1] * fl.y)
                        .sum();
                }
                Vec2::new(y[0], y[1])
            })
            .collect()
    }

    /// Semi-smooth Newton on `R(Δ) = Δ − Δ_free − x S f(Δ) = 0`; each
    /// step solves `(I − x S J) d = −R` over the active points `C` (an
    /// inactive point's jump follows: `d_O = −R_O + x S_OC J_C d_C`) and is
    /// halved until `|R|` falls (Armijo): sticking and sliding can
    /// otherwise swap back and forth. Exact once a whole step keeps every
    /// point's regime where the law is affine (a point closed, or open, at
    /// both ends of a Newmark step); a point that closes or opens within
    /// the step has a smooth mean force and converges quadratically.
    /// Returns the iterations and the law at the solution (forces × x).
    fn newton(
        &self,
        free: &[Vec2],
        old: &[Vec2],
        law: Law,
        x: f64,
    ) -> Result<(usize, Vec<Eval>), Unsettled> {
        let m = free.len();
        let m2 = 2 * m;
        let eval = |d: &[Vec2]| -> Vec<Eval> {
            (0..m)
                .map(|k| {
                    let mut e = self.points[k].eval(d[k], old[k], self.shear[k], law);
                    e.f = e.f * x;
                    e.jac.iter_mut().for_each(|j| *j *= x);
                    e
                })
                .collect()
        };
        let residual = |d: &[Vec2], e: &[Eval]| -> (Vec<Vec2>, f64) {
            let f: Vec<Vec2> = e.iter().map(|x| x.f).collect();
            let sf = self.s_times(&f);
            let r: Vec<Vec2> = (0..m).map(|k| -(d[k] - free[k] - sf[k])).collect();
            let phi = r.iter().map(|x| x.dot(*x)).sum::<f64>();
            (r, phi)
        };
        let scale = free.iter().chain(old).map(|x| x.dot(*x)).sum::<f64>();
        let mut d = free.to_vec();
        let mut e = eval(&d);
        let (mut r, mut phi) = residual(&d, &e);
        for iter in 1..=MAX_ITER {
            let closed: Vec<usize> = (0..m).filter(|&k| e[k].regime != 0).collect();
            let c2 = 2 * closed.len();
            let mut mat = vec![0.0; c2 * c2];
            let mut rhs: Vec<f64> = closed.iter().flat_map(|&k| [r[k].x, r[k].y]).collect();
            for (i, &k) in closed.iter().enumerate() {
                for a in 0..2 {
                    let row = &self.s[(2 * k + a) * m2..(2 * k + a + 1) * m2];
                    let ri = 2 * i + a;
                    for (j, &l) in closed.iter().enumerate() {
                        let (x, y, jac) = (row[2 * l], row[2 * l + 1], &e[l].jac);
                        mat[ri * c2 + 2 * j] = -(x * jac[0] + y * jac[2]);
                        mat[ri * c2 + 2 * j + 1] = -(x * jac[1] + y * jac[3]);
                    }
                    mat[ri * c2 + ri] += 1.0;
                }
            }
            gauss_solve(&mut mat, &mut rhs, c2);
            let mut jd = vec![Vec2::ZERO; m];
            for (i, &k) in closed.iter().enumerate() {
                let dc = Vec2::new(rhs[2 * i], rhs[2 * i + 1]);
                let j = &e[k].jac;
                jd[k] = Vec2::new(j[0] * dc.x + j[1] * dc.y, j[2] * dc.x + j[3] * dc.y);
            }
            let sjd = self.s_times(&jd);
            let mut step: Vec<Vec2> = (0..m).map(|k| r[k] + sjd[k]).collect();
            for (i, &k) in closed.iter().enumerate() {
                step[k] = Vec2::new(rhs[2 * i], rhs[2 * i + 1]);
            }
            let mut t = 1.0;
            loop {
                let trial: Vec<Vec2> = (0..m).map(|k| d[k] + step[k] * t).collect();
                let et = eval(&trial);
                let (rt, pt) = residual(&trial, &et);
                if pt <= (1.0 - 1e-4 * t) * phi || t < 1.0 / 64.0 {
                    let same = et.iter().zip(&e).all(|(a, b)| a.regime == b.regime);
                    (d, e, r, phi) = (trial, et, rt, pt);
                    let exact = t == 1.0 && same && e.iter().all(|x| x.affine);
                    if exact || phi <= TOL * TOL * scale {
                        return Ok((iter, e));
                    }
                    break;
                }
                t *= 0.5;
            }
        }
        if phi <= ACCEPT * ACCEPT * scale {
            return Ok((MAX_ITER, e));
        }
        Err(Unsettled {
            residual: phi.sqrt(),
            scale: scale.sqrt(),
        })
    }

    /// The forces of the faces in contact as loads per thickness `t` on
    /// each face, `(x_L, c f/t)` and `(x_R, −c f/t)` at the face nodes of
    /// every closed point, for the interaction integral at the tip at
    /// `tip = (crack, distance along it)`: `c` turns the point's force
    /// into the integral of its traction over its stretch `[r_a, r_b]` of
    /// the crack against the auxiliary field's `r^(−1/2)`,
    /// `c = 2 (√r_b − √r_a) √r / (r_b − r_a)` (1 away from the tip; 1.63
    /// at the point next to it, whose stretch reaches the tip).
    pub fn face_forces(&self, t: f64, tip: (usize, f64)) -> Vec<(Vec2, Vec2)> {
        let weight = |p: &FacePoint| {
            if p.crack != tip.0 {
                return 1.0;
            }
            let r = |s: f64| (s - tip.1).abs();
            let (ra, rb) = (
                r(p.span[0]).min(r(p.span[1])),
                r(p.span[0]).max(r(p.span[1])),
            );
            2.0 * (rb.sqrt() - ra.sqrt()) * r(p.arc).sqrt() / (rb - ra)
        };
        self.points
            .iter()
            .zip(&self.force)
            .filter(|(_, f)| **f != Vec2::ZERO)
            .flat_map(|(p, f)| {
                let g = *f * (weight(p) / t);
                [(p.at[0], g), (p.at[1], g * -1.0)]
            })
            .collect()
    }

    /// Energy of the face springs at the present state:
    /// `Σ (f_n² + f_t²) / (2k)`.
    pub fn energy(&self) -> f64 {
        self.points
            .iter()
            .zip(&self.force)
            .map(|(p, f)| 0.5 * f.dot(*f) / p.k)
            .sum()
    }
}
