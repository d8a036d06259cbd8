//! The contacts of the present state, of every kind, with their forces:
//! what force-chain plots, ParaView frames and Python users read.

use crate::coupling::CoupledModel;
use crate::dem::Granular;
use crate::dem::contact::normal_between;
use crate::geom::Vec2;

/// What a disc touches.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[repr(u8)]
pub enum ContactKind {
    /// Another disc (`other`: its index).
    DiscDisc = 0,
    /// A rigid wall (`other`: the wall's index).
    DiscWall = 1,
    /// A continuum body's boundary (`other`: the body's index).
    DiscBody = 2,
}

/// One closed contact (overlap > 0).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContactView {
    /// What the disc touches.
    pub kind: ContactKind,
    /// Index of the disc in scenario order, from 0 (the files number it
    /// `disc + 1`).
    pub disc: usize,
    /// The other side: the index (from 0, in scenario order) of a disc, a
    /// wall or a body; the files number it `other + 1`.
    pub other: usize,
    /// Contact point: on the disc's surface along the normal (disc–disc),
    /// on the wall or the body's boundary.
    pub point: Vec2,
    /// Unit normal from the disc towards the other side.
    pub normal: Vec2,
    /// Overlap δ.
    pub overlap: f64,
    /// Elastic normal force `k_n δ` (compression positive).
    pub normal_elastic: f64,
    /// Total normal force, spring + dashpot (Eq. 35).
    pub normal_total: f64,
    /// Shear spring force along `t = perp(n)` (the incremental history of
    /// Eq. 36, capped by Eq. 37; without the shear dashpot).
    pub shear: f64,
}

impl ContactView {
    /// Force on the disc from its elastic parts: `−F_n n + F_s t`.
    pub fn force_on_disc(&self) -> Vec2 {
        self.normal * (-self.normal_elastic) + self.normal.perp() * self.shear
    }
}

/// All closed contacts: disc–disc, disc–wall, then disc–body.
pub fn all(g: Option<&Granular>, m: Option<&CoupledModel>) -> Vec<ContactView> {
    let mut out = Vec::new();
    if let Some(g) = g {
        let p = &g.particles;
        for (k, (i, j)) in g.contacts.pairs().enumerate() {
            let (n, dist) = normal_between(p.pos[i], p.pos[j]);
            let delta = p.radius[i] + p.radius[j] - dist;
            if delta <= 0.0 {
                continue;
            }
            let (el, tot) = g.normal_force(i, j);
            out.push(ContactView {
                kind: ContactKind::DiscDisc,
                disc: p.id[i] as usize,
                other: p.id[j] as usize,
                point: p.pos[i] + n * p.radius[i],
                normal: n,
                overlap: delta,
                normal_elastic: el,
                normal_total: tot,
                shear: g.contacts.shear[k],
            });
        }
        for q in &g.contacts.walls {
            let Some(wc) = g.wall_contact(q) else {
                continue;
            };
            let (d, w) = (q.disc as usize, q.wall as usize);
            out.push(ContactView {
                kind: ContactKind::DiscWall,
                disc: p.id[d] as usize,
                other: w,
                point: wc.point,
                normal: wc.normal,
                overlap: wc.overlap,
                normal_elastic: wc.elastic,
                normal_total: wc.total,
                shear: q.fs,
            });
        }
    }
    if let Some(m) = m {
        for c in &m.contacts {
            out.push(ContactView {
                kind: ContactKind::DiscBody,
                disc: c.disc as usize,
                other: c.body as usize,
                point: c.point,
                normal: c.normal,
                overlap: c.overlap,
                normal_elastic: c.fn_elastic,
                normal_total: c.fn_total,
                shear: c.fs,
            });
        }
    }
    out
}
