//! Stress, porosity, coordination number and fabric of a region of the
//! assembly — the measurement circles / rectangles of PFC and Yade.
//!
//! For the discs whose **centre** lies in the region (rectangle: `x0 ≤ x <
//! x1`, `y0 ≤ y < y1`, so that adjacent rectangles share no disc; circle:
//! `|x − c| < R`), counting **every contact of those discs** — with other
//! discs (inside the region or not), walls and bodies:
//!
//! * average stress, Love–Weber (Love 1927; Weber 1966; Christoffersen,
//!   Mehrabadi & Nemat-Nasser 1981; Bagi 1996):
//!   `σ = −(1/(A t)) Σ_p Σ_{c∈p} f_c ⊗ l_c`, with `f_c` the contact force on
//!   disc p, `l_c = x_c − x_p` its branch vector from the centre to the
//!   contact point (for a disc of a clump, from the clump's centre of
//!   mass: the clump's internal forces are then counted), A the region's area and t the disc thickness (forces
//!   act on the whole disc length). Sign: **compression positive** (the
//!   geomechanics convention; hence the minus). `σ_xy` is the symmetric
//!   part `½(σ_xy + σ_yx)`: the two differ by the discs' out-of-balance
//!   moments (and the rolling-resistance moments, which are not in the
//!   formula);
//! * porosity `1 − Σ_p A_p∩region / A`: the part of each disc's area
//!   inside the region (exact circle–rectangle and circle–circle
//!   intersections), whatever its centre; overlaps between discs are
//!   counted twice (they are small), except within a clump, whose discs
//!   count with the factor (union area) / (sum of their areas);
//! * coordination number `Z = N_c / N_p`: contacts per disc, N_p the discs
//!   with centre inside, N_c their contacts (a contact between two discs
//!   inside counts once for each); rattlers are not excluded;
//! * fabric tensor `F = (1/N_c) Σ_c n_c ⊗ n_c` (Satake 1982; Oda 1982), n
//!   the unit contact normal, over the same contacts; `tr F = 1`.
//!
//! The contact point of two discs is the middle of their overlap,
//! `x_c = x_i + (r_i − δ/2) n` (PFC, Yade), so that the two discs share
//! it; that of a disc and a wall or body is on the wall or the body's
//! boundary. With a common contact point the forces between discs inside
//! the region cancel in pairs, and at equilibrium without gravity
//! `Σ_p Σ_c f_c ⊗ l_c = Σ_boundary f ⊗ x`: a region that holds every disc
//! of a box measures exactly the stress the walls carry.
//!
//! The contact forces are those of the present state: the normal force
//! `k_n δ + c_n δ̇` (Eq. 35, the dashpot with the half-step velocities),
//! and the shear spring force (the contact's history; a shear dashpot is
//! not included). Disc–body contacts come from the coupling as
//! [`OuterContact`]s. With no disc inside, Z and F are 0.

use super::Granular;
use super::clumps::NO_CLUMP;
use super::contact::normal_between;
use crate::geom::Vec2;
use crate::geom::exact_sum::ExactSum;

/// The region of a measurement.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Region {
    /// Axis-aligned rectangle `[lo, hi)`.
    Rectangle {
        /// Lower-left corner.
        lo: Vec2,
        /// Upper-right corner.
        hi: Vec2,
    },
    /// Circle.
    Circle {
        /// Centre.
        centre: Vec2,
        /// Radius.
        radius: f64,
    },
}

impl Region {
    /// Area A.
    pub fn area(&self) -> f64 {
        match *self {
            Region::Rectangle { lo, hi } => (hi.x - lo.x) * (hi.y - lo.y),
            Region::Circle { radius, .. } => std::f64::consts::PI * radius * radius,
        }
    }

    /// Is the point inside (rectangle `[lo, hi)`, circle open)?
    #[inline]
    pub fn contains(&self, p: Vec2) -> bool {
        match *self {
            Region::Rectangle { lo, hi } => p.x >= lo.x && p.x < hi.x && p.y >= lo.y && p.y < hi.y,
            Region::Circle { centre, radius } => (p - centre).norm2() < radius * radius,
        }
    }

    /// Area of the disc of centre `c` and radius `r` inside the region
    /// (exact).
    pub fn disc_area_inside(&self, c: Vec2, r: f64) -> f64 {
        let full = std::f64::consts::PI * r * r;
        match *self {
            Region::Rectangle { lo, hi } => {
                if c.x - r >= hi.x || c.x + r <= lo.x || c.y - r >= hi.y || c.y + r <= lo.y {
                    return 0.0;
                }
                if c.x - r >= lo.x && c.x + r <= hi.x && c.y - r >= lo.y && c.y + r <= hi.y {
                    return full;
                }
                let corners = [lo, Vec2::new(hi.x, lo.y), hi, Vec2::new(lo.x, hi.y)];
                let mut s = 0.0;
                for k in 0..4 {
                    s += edge_area(corners[k] - c, corners[(k + 1) % 4] - c, r);
                }
                s.abs().min(full)
            }
            Region::Circle { centre, radius } => lens_area((c - centre).norm(), radius, r),
        }
    }
}

/// Signed area of the disc of radius `r` about the origin within the
/// triangle (origin, p, q): the edge term of the area of a polygon ∩ disc
/// by Green's theorem (the triangle where the edge is inside the circle,
/// the circular sector where it is outside).
fn edge_area(p: Vec2, q: Vec2, r: f64) -> f64 {
    let d = q - p;
    let a = d.norm2();
    let b = p.dot(d);
    let c = p.norm2() - r * r;
    // crossings of |p + s d| = r for s in (0, 1), in order
    let mut ts = [0.0, 1.0, 1.0, 1.0];
    let mut n = 1;
    let disc = b * b - a * c;
    if a > 0.0 && disc > 0.0 {
        let h = disc.sqrt();
        for s in [(-b - h) / a, (-b + h) / a] {
            if s > 0.0 && s < 1.0 {
                ts[n] = s;
                n += 1;
            }
        }
    }
    ts[n] = 1.0;
    let mut area = 0.0;
    for k in 0..n {
        let (u, v) = (p + d * ts[k], p + d * ts[k + 1]);
        let m = p + d * (0.5 * (ts[k] + ts[k + 1]));
        area += if m.norm2() <= r * r {
            0.5 * u.cross(v)
        } else {
            0.5 * r * r * u.cross(v).atan2(u.dot(v))
        };
    }
    area
}

/// Area of the intersection of two circles of radii `ra`, `rb` whose
/// centres are `d` apart (the lens).
fn lens_area(d: f64, ra: f64, rb: f64) -> f64 {
    use std::f64::consts::PI;
    if d >= ra + rb {
        return 0.0;
    }
    if d <= (ra - rb).abs() {
        let r = ra.min(rb);
        return PI * r * r;
    }
    let ca = ((d * d + ra * ra - rb * rb) / (2.0 * d * ra)).clamp(-1.0, 1.0);
    let cb = ((d * d + rb * rb - ra * ra) / (2.0 * d * rb)).clamp(-1.0, 1.0);
    let k = ((-d + ra + rb) * (d + ra - rb) * (d - ra + rb) * (d + ra + rb)).max(0.0);
    ra * ra * ca.acos() + rb * rb * cb.acos() - 0.5 * k.sqrt()
}

/// A contact of a disc with something the assembly does not hold (a
/// continuum body's boundary, from the coupling).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OuterContact {
    /// Slot of the disc.
    pub slot: usize,
    /// Contact point.
    pub point: Vec2,
    /// Unit normal from the disc towards the other side.
    pub normal: Vec2,
    /// Force on the disc.
    pub force: Vec2,
}

/// One column of a measurement.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Quantity {
    /// σ_xx, compression positive (`sxx_cpos`).
    Sxx,
    /// σ_yy, compression positive (`syy_cpos`).
    Syy,
    /// σ_xy (symmetric part), compression positive (`sxy_cpos`).
    Sxy,
    /// Porosity.
    Porosity,
    /// Coordination number.
    Coordination,
    /// Fabric F_xx.
    Fxx,
    /// Fabric F_yy.
    Fyy,
    /// Fabric F_xy.
    Fxy,
}

impl Quantity {
    /// Every quantity, in the order of the history columns.
    pub const ALL: [Quantity; 8] = [
        Quantity::Sxx,
        Quantity::Syy,
        Quantity::Sxy,
        Quantity::Porosity,
        Quantity::Coordination,
        Quantity::Fxx,
        Quantity::Fyy,
        Quantity::Fxy,
    ];

    /// Its name (the history column's suffix): `sxx_cpos` (the stresses
    /// say their sign: compression positive), …, `fxy`.
    pub fn name(self) -> &'static str {
        match self {
            Quantity::Sxx => "sxx_cpos",
            Quantity::Syy => "syy_cpos",
            Quantity::Sxy => "sxy_cpos",
            Quantity::Porosity => "porosity",
            Quantity::Coordination => "coordination",
            Quantity::Fxx => "fxx",
            Quantity::Fyy => "fyy",
            Quantity::Fxy => "fxy",
        }
    }

    /// The quantity called `name`.
    pub fn from_name(name: &str) -> Option<Quantity> {
        Quantity::ALL.into_iter().find(|q| q.name() == name)
    }
}

/// What the contacts of the discs inside a region give ([module](self)).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ContactMeasure {
    /// `[σ_xx, σ_yy, σ_xy]`, compression positive.
    pub stress: [f64; 3],
    /// Coordination number Z.
    pub coordination: f64,
    /// `[F_xx, F_yy, F_xy]`.
    pub fabric: [f64; 3],
    /// Discs with centre inside, N_p.
    pub discs: usize,
    /// Their contacts, N_c.
    pub contacts: usize,
}

impl ContactMeasure {
    /// The value of `q` (porosity: NaN, see [`porosity`]).
    pub fn get(&self, q: Quantity) -> f64 {
        match q {
            Quantity::Sxx => self.stress[0],
            Quantity::Syy => self.stress[1],
            Quantity::Sxy => self.stress[2],
            Quantity::Porosity => f64::NAN,
            Quantity::Coordination => self.coordination,
            Quantity::Fxx => self.fabric[0],
            Quantity::Fyy => self.fabric[1],
            Quantity::Fxy => self.fabric[2],
        }
    }
}

/// Porosity of the region: `1 − Σ_p |disc_p ∩ region| / A` over every disc.
/// A clump's discs count with the factor (area of the union) / (sum of
/// the discs' areas), so that a clump inside the region counts its area
/// once.
pub fn porosity(g: &Granular, region: &Region) -> f64 {
    1.0 - solid_area(g, region).value() / region.area()
}

/// `Σ_p |disc_p ∩ region|` of [`porosity`], exactly, over the discs that
/// are not ghosts (a part's share, see [`Granular::energy_sums`]).
pub fn solid_area(g: &Granular, region: &Region) -> ExactSum {
    let p = &g.particles;
    let c = &g.clumps;
    let share: Vec<f64> = (0..c.len())
        .map(|k| {
            let discs: f64 = c
                .members_of(k)
                .iter()
                .map(|&id| p.mass[g.slot(id as usize)])
                .sum();
            c.mass[c.row_of(k)] / discs
        })
        .collect();
    (0..p.len())
        .filter(|&k| !p.is_ghost(k))
        .map(|k| {
            let a = region.disc_area_inside(p.pos[k], p.radius[k]);
            match p.clump[k] {
                NO_CLUMP => a,
                ck => a * share[ck as usize],
            }
        })
        .collect()
}

/// The sums of a region's [`ContactMeasure`]: `Σ f ⊗ l` as `[xx, xy, yx,
/// yy]`, `Σ n ⊗ n` as `[xx, yy, xy]` (exact sums), the contacts and the
/// discs. Those of the parts of a divided assembly, merged, are those of
/// the whole.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ContactSums {
    /// `Σ f ⊗ l` as `[xx, xy, yx, yy]`.
    pub fl: [ExactSum; 4],
    /// `Σ n ⊗ n` as `[xx, yy, xy]`.
    pub nn: [ExactSum; 3],
    /// Contacts, N_c.
    pub contacts: usize,
    /// Discs with centre inside, N_p.
    pub discs: usize,
}

impl ContactSums {
    /// Add the sums of another part.
    pub fn merge(&mut self, o: &ContactSums) {
        self.fl.iter_mut().zip(&o.fl).for_each(|(a, b)| a.merge(b));
        self.nn.iter_mut().zip(&o.nn).for_each(|(a, b)| a.merge(b));
        self.contacts += o.contacts;
        self.discs += o.discs;
    }

    /// The measurement of `region` (of an assembly `thickness` thick).
    pub fn finish(&self, region: &Region, thickness: f64) -> ContactMeasure {
        let s = self.fl.each_ref().map(ExactSum::value);
        let fab = self.nn.each_ref().map(ExactSum::value);
        let (nc, np) = (self.contacts, self.discs);
        let at = -1.0 / (region.area() * thickness);
        let per = |v: f64, n: usize| if n > 0 { v / n as f64 } else { 0.0 };
        ContactMeasure {
            stress: [s[0] * at, s[3] * at, 0.5 * (s[1] + s[2]) * at],
            coordination: per(nc as f64, np),
            fabric: [per(fab[0], nc), per(fab[1], nc), per(fab[2], nc)],
            discs: np,
            contacts: nc,
        }
    }
}

/// Love–Weber stress, coordination number and fabric of the discs whose
/// centre is in `region` ([module](self)), from the present state, their
/// disc–disc and disc–wall contacts and the `outer` contacts (disc–body).
pub fn contacts(
    g: &Granular,
    region: &Region,
    outer: impl IntoIterator<Item = OuterContact>,
) -> ContactMeasure {
    contact_sums(g, region, outer).finish(region, g.thickness)
}

/// The sums behind [`contacts`], over the discs that are not ghosts and
/// the pairs whose first disc is not one (a part's share, see
/// [`Granular::energy_sums`]). One pass over the contact list.
pub fn contact_sums(
    g: &Granular,
    region: &Region,
    outer: impl IntoIterator<Item = OuterContact>,
) -> ContactSums {
    let p = &g.particles;
    let own = |k: usize| !p.is_ghost(k);
    // the centre of the body disc k belongs to: a clump's, or its own
    let centre = |k: usize| match p.clump[k] {
        NO_CLUMP => p.pos[k],
        c => g.clumps.pos[g.clumps.row_of(c as usize)],
    };
    let mut sums = ContactSums::default();
    let mut add = |f: Vec2, l: Vec2, n: Vec2| {
        let s = &mut sums;
        s.fl[0].add(f.x * l.x);
        s.fl[1].add(f.x * l.y);
        s.fl[2].add(f.y * l.x);
        s.fl[3].add(f.y * l.y);
        s.nn[0].add(n.x * n.x);
        s.nn[1].add(n.y * n.y);
        s.nn[2].add(n.x * n.y);
        s.contacts += 1;
    };
    for (k, (i, j)) in g.contacts.pairs().enumerate() {
        if !own(i) {
            continue;
        }
        let (in_i, in_j) = (region.contains(p.pos[i]), region.contains(p.pos[j]));
        if !in_i && !in_j {
            continue;
        }
        let (n, dist) = normal_between(p.pos[i], p.pos[j]);
        let delta = p.radius[i] + p.radius[j] - dist;
        if delta <= 0.0 {
            continue;
        }
        let (_, fn_tot) = g.normal_force(i, j);
        // force on i (ContactForce's convention), at the middle of the overlap
        let f = n * (-fn_tot) + n.perp() * g.contacts.shear[k];
        let xc = p.pos[i] + n * (p.radius[i] - 0.5 * delta);
        if in_i {
            add(f, xc - centre(i), n);
        }
        if in_j {
            add(-f, xc - centre(j), n);
        }
    }
    for q in &g.contacts.walls {
        let d = q.disc as usize;
        if !own(d) || !region.contains(p.pos[d]) {
            continue;
        }
        let Some(wc) = g.wall_contact(q) else {
            continue;
        };
        let (c, n, fn_tot) = (wc.point, wc.normal, wc.total);
        add(n * (-fn_tot) + n.perp() * q.fs, c - centre(d), n);
    }
    for o in outer {
        if own(o.slot) && region.contains(p.pos[o.slot]) {
            add(o.force, o.point - centre(o.slot), o.normal);
        }
    }
    sums.discs = (0..p.len())
        .filter(|&k| own(k) && region.contains(p.pos[k]))
        .count();
    sums
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    #[test]
    fn disc_area_in_a_rectangle() {
        let r = Region::Rectangle {
            lo: Vec2::new(0.0, 0.0),
            hi: Vec2::new(4.0, 2.0),
        };
        let a = |x: f64, y: f64, rad: f64| r.disc_area_inside(Vec2::new(x, y), rad);
        assert_eq!(a(1.0, 1.0, 0.5), PI * 0.25);
        assert_eq!(a(9.0, 1.0, 0.5), 0.0);
        // centre on an edge: half; on a corner: a quarter
        assert!((a(0.0, 1.0, 0.5) - PI * 0.125).abs() < 1e-15);
        assert!((a(4.0, 2.0, 0.5) - PI * 0.0625).abs() < 1e-15);
        // a chord: segment area r² acos(h/r) − h √(r² − h²) outside
        let (rad, h) = (0.8f64, 0.3);
        let seg = rad * rad * (h / rad).acos() - h * (rad * rad - h * h).sqrt();
        assert!((a(4.0 - h, 1.0, rad) - (PI * rad * rad - seg)).abs() < 1e-14);
        // a disc larger than the rectangle covers it
        assert!((a(2.0, 1.0, 10.0) - 8.0).abs() < 1e-12);
        // cut by two edges (a corner inside the disc): against a fine grid
        let (cx, cy, rad) = (3.7, 1.8, 0.6);
        let m = 2000;
        let mut inside = 0usize;
        for i in 0..m {
            for j in 0..m {
                let x = cx - rad + 2.0 * rad * (i as f64 + 0.5) / m as f64;
                let y = cy - rad + 2.0 * rad * (j as f64 + 0.5) / m as f64;
                if (x - cx).powi(2) + (y - cy).powi(2) < rad * rad && x < 4.0 && y < 2.0 {
                    inside += 1;
                }
            }
        }
        let grid = inside as f64 * (2.0 * rad / m as f64).powi(2);
        assert!(
            (a(cx, cy, rad) - grid).abs() < 2e-4,
            "{} {grid}",
            a(cx, cy, rad)
        );
    }

    #[test]
    fn disc_area_in_a_circle() {
        let r = Region::Circle {
            centre: Vec2::new(1.0, 1.0),
            radius: 2.0,
        };
        let a = |x: f64, y: f64, rad: f64| r.disc_area_inside(Vec2::new(x, y), rad);
        assert_eq!(a(1.5, 1.0, 0.5), PI * 0.25);
        assert_eq!(a(5.0, 1.0, 0.5), 0.0);
        // two equal circles of radius ρ at distance ρ: (2π/3 − √3/2) ρ²
        let rr = Region::Circle {
            centre: Vec2::ZERO,
            radius: 1.0,
        };
        let lens = rr.disc_area_inside(Vec2::new(1.0, 0.0), 1.0);
        assert!((lens - (2.0 * PI / 3.0 - 3f64.sqrt() / 2.0)).abs() < 1e-15);
    }

    #[test]
    fn quantity_names_round_trip() {
        for q in Quantity::ALL {
            assert_eq!(Quantity::from_name(q.name()), Some(q));
        }
        assert_eq!(Quantity::from_name("szz"), None);
    }
}
