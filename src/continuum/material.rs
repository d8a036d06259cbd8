//! The linear elastic material of a continuum body and the true fields
//! sampled at a point (shared by the EFG and FE methods).

use super::body_params::{BodyParams, Plane};
use super::quadrature;
use crate::geom::Vec2;

/// Isotropic elasticity matrix `D` (Eq. 31 plane stress, Eq. 32 plane
/// strain) as `[D11, D12, D22, D33]`.
pub fn elasticity(e: f64, nu: f64, plane_strain: bool) -> [f64; 4] {
    if plane_strain {
        let c = e / ((1.0 + nu) * (1.0 - 2.0 * nu));
        [
            c * (1.0 - nu),
            c * nu,
            c * (1.0 - nu),
            c * (1.0 - 2.0 * nu) / 2.0,
        ]
    } else {
        let c = e / (1.0 - nu * nu);
        [c, c * nu, c, c * (1.0 - nu) / 2.0]
    }
}

/// Material data of a body.
#[derive(Debug, Clone, Copy)]
pub struct Material {
    /// Young's modulus E.
    pub e: f64,
    /// Poisson's ratio ν.
    pub nu: f64,
    /// Mass density ρ (per unit volume; the mass matrix multiplies by the
    /// thickness).
    pub density: f64,
    /// Out-of-plane thickness t; stiffness, mass and body force scale with it.
    pub thickness: f64,
    /// Plane stress or plane strain.
    pub plane: Plane,
    /// Damping coefficient c (Eq. 24).
    pub damping: f64,
    /// `[D11, D12, D22, D33]` (Eq. 31 or 32).
    pub d: [f64; 4],
}

impl Material {
    /// The material of a body: `elastic`, `damping`, and `D` of Eq. (31)
    /// (plane stress) or Eq. (32) (plane strain).
    pub fn of_params(spec: &BodyParams) -> Material {
        let el = spec.elastic;
        Material {
            e: el.e,
            nu: el.nu,
            density: el.density,
            thickness: el.thickness,
            plane: el.plane,
            damping: spec.damping,
            d: elasticity(el.e, el.nu, el.plane == Plane::Strain),
        }
    }
    /// Stress `D ε` from engineering strain `(ε_xx, ε_yy, γ_xy)`.
    pub fn stress(&self, e: [f64; 3]) -> [f64; 3] {
        let [d11, d12, d22, d33] = self.d;
        [d11 * e[0] + d12 * e[1], d12 * e[0] + d22 * e[1], d33 * e[2]]
    }
}

/// True (interpolated) fields at a point.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Sample {
    /// Displacement `u(x) = Σ φ_I(x) u_I` (Eq. 12).
    pub u: Vec2,
    /// Velocity `Σ φ_I(x) u̇_I`.
    pub v: Vec2,
    /// Engineering strain `(ε_xx, ε_yy, γ_xy) = B u` (E5).
    pub strain: [f64; 3],
    /// Stress `(σ_xx, σ_yy, σ_xy) = D ε`.
    pub stress: [f64; 3],
}

impl Sample {
    /// The field named by a point-probe quantity
    /// (the point quantities of a probe).
    pub fn field(&self, q: &str) -> Option<f64> {
        Some(match q {
            "ux" => self.u.x,
            "uy" => self.u.y,
            "vx" => self.v.x,
            "vy" => self.v.y,
            "exx" => self.strain[0],
            "eyy" => self.strain[1],
            "gxy" => self.strain[2],
            "sxx" => self.stress[0],
            "syy" => self.stress[1],
            "sxy" => self.stress[2],
            _ => return None,
        })
    }
}

/// Relative energy-norm error `‖ε − ε_ex‖_E / ‖ε_ex‖_E` of the fields given
/// by `sample` against an exact stress field (exact strain recovered with
/// `D⁻¹`), integrated with `gauss`² points on `cells` over the rectangle.
/// Shared by the EFG and FE bodies.
pub fn energy_error_of<E>(
    material: &Material,
    origin: Vec2,
    size: Vec2,
    cells: [usize; 2],
    gauss: usize,
    mut sample: impl FnMut(Vec2) -> Result<Sample, E>,
    exact_stress: impl Fn(Vec2) -> [f64; 3],
) -> Result<f64, E> {
    let [d11, d12, _d22, d33] = material.d;
    // D⁻¹ for the isotropic D
    let det = d11 * d11 - d12 * d12;
    let compl = |s: [f64; 3]| {
        [
            (d11 * s[0] - d12 * s[1]) / det,
            (d11 * s[1] - d12 * s[0]) / det,
            s[2] / d33,
        ]
    };
    let (mut num, mut den) = (0.0, 0.0);
    for q in quadrature::domain_points(origin, size, cells, gauss) {
        let s = sample(q.x)?;
        let se = exact_stress(q.x);
        let ee = compl(se);
        let ds = [
            s.stress[0] - se[0],
            s.stress[1] - se[1],
            s.stress[2] - se[2],
        ];
        let de = [
            s.strain[0] - ee[0],
            s.strain[1] - ee[1],
            s.strain[2] - ee[2],
        ];
        num += q.w * (ds[0] * de[0] + ds[1] * de[1] + ds[2] * de[2]);
        den += q.w * (se[0] * ee[0] + se[1] * ee[1] + se[2] * ee[2]);
    }
    Ok((num / den).sqrt())
}
