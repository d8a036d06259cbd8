//! Probes: quantities of the state a history records, bound to what they
//! measure (disc ids, wall and body indices, sampling points). The scenario
//! binds them by name; [`Model::probe`](super::Model::probe) evaluates one.

use super::body::{At, BodyRef};
use crate::coupling::CoupledModel;
use crate::dem::Granular;
use crate::dem::measure::{self, OuterContact, Quantity, Region};
use crate::dem::walls::Wall;
use crate::geom::Vec2;
use crate::geom::exact_sum::ExactSum;

/// A quantity of the state, bound to its target.
#[derive(Debug)]
pub enum Probe {
    /// A field (`ux`, `sxx`, …, see [`crate::continuum::Sample::field`]) at
    /// a bound point of body `body`.
    BodyPoint {
        /// Body index.
        body: usize,
        /// The bound reference point.
        at: At,
        /// The point.
        point: Vec2,
        /// The body's generation `at` was bound in ([`BodyRef::generation`]):
        /// a body rebuilt by crack growth is sampled afresh.
        generation: usize,
        /// The field's name.
        field: String,
    },
    /// A crack quantity of EFG body `body`: `k1`, `k2`, `k_eq` (stress
    /// intensity factors at the tip, maximum hoop-stress `K_eq`),
    /// `crack_length` (the polyline's length), `fracture_energy` (body-wide,
    /// released by growth so far).
    Crack {
        /// Body index.
        body: usize,
        /// Crack index in the body.
        crack: usize,
        /// The crack's end (0: first point, 1: last point).
        end: usize,
        /// The quantity's name.
        quantity: String,
    },
    /// `kinetic_energy`, `strain_energy` or `total_energy` of a body.
    BodyEnergy {
        /// Body index.
        body: usize,
        /// The energy's name.
        quantity: String,
    },
    /// A drive of body `body` (its `index`-th drive, [`BodyRef::drives`]):
    /// `drive_ux`/`drive_uy` (position), `drive_vx`/`drive_vy` (velocity
    /// of the last step), `drive_fx`/`drive_fy` (force measured when the
    /// last step was decided).
    Drive {
        /// Body index.
        body: usize,
        /// Index among the body's drives.
        index: usize,
        /// The quantity's name.
        quantity: String,
    },
    /// Total force of the discs on body `body` (`y`: the y component).
    BodyForce {
        /// Body index.
        body: usize,
        /// The y component if true, else the x component.
        y: bool,
    },
    /// A disc quantity (`x`, `y`, `vx`, `vy`, `theta`, `omega`; `ux`, `uy`:
    /// displacement from `x0`) of the disc with scenario id `id` (0-based).
    Disc {
        /// Scenario disc id (0-based), not the slot.
        id: usize,
        /// The quantity's name.
        quantity: String,
        /// The disc's centre when the probe was bound (at build, t = 0),
        /// for `ux`, `uy`.
        x0: Vec2,
    },
    /// Normal force between discs `a` and `b` (ids): elastic `k_n δ`, or
    /// `total` with the dashpot.
    Contact {
        /// First disc id.
        a: usize,
        /// Second disc id.
        b: usize,
        /// With the dashpot (`k_n δ + β k_n δ̇`) if true, else `k_n δ`.
        total: bool,
    },
    /// `wall_fx`, `wall_fy`, `wall_x`, `wall_y`, `wall_stress`,
    /// `wall_length` of wall `wall`.
    Wall {
        /// Wall index.
        wall: usize,
        /// The quantity's name.
        quantity: String,
    },
    /// A quantity of the discs in a region ([`measure`]): stress,
    /// porosity, coordination number or fabric. Porosity is a pass over the
    /// discs; the other quantities share one pass over the contacts per
    /// state through `memo` (one per region).
    Measure {
        /// The region.
        region: Region,
        /// The quantity.
        quantity: Quantity,
        /// The last contact measurement of the region, shared by its
        /// columns.
        memo: std::sync::Arc<MeasureMemo>,
    },
    /// An assembly-wide quantity: `kinetic`, `rotational`, `spring`,
    /// `gravity_energy`, `total_energy`, `contacts` (disc–body contacts
    /// included).
    Global {
        /// The quantity's name.
        quantity: String,
    },
}

impl Probe {
    /// The sign convention of a stress probe, for the summary: a body's
    /// stress is tension positive (continuum convention), the discs'
    /// (`[[measure]]`) and a wall's compression positive.
    pub fn sign(&self) -> Option<&'static str> {
        use measure::Quantity as Q;
        match self {
            Probe::BodyPoint { field, .. } if matches!(field.as_str(), "sxx" | "syy" | "sxy") => {
                Some("tension positive")
            }
            Probe::Measure {
                quantity: Q::Sxx | Q::Syy | Q::Sxy,
                ..
            } => Some("compression positive"),
            Probe::Wall { quantity, .. } if quantity == "wall_stress" => {
                Some("compression positive")
            }
            _ => None,
        }
    }
}

/// The last [`measure::contacts`] of a region with a key of the state it
/// was taken from: the columns of one `[[measure]]` read one pass over the
/// contacts instead of one each. The key mixes the step count, the time,
/// the neighbour-list rebuild count and sums of every disc's position,
/// velocity and spin bits (a streaming pass over the discs, a tenth of
/// the measurement), so a state changed in any other way is measured
/// afresh.
#[derive(Debug, Default)]
pub struct MeasureMemo(std::sync::Mutex<Option<(u64, measure::ContactSums)>>);

impl MeasureMemo {
    /// The sums of `region` in this state, from the memo if the state is
    /// the one they were taken from.
    fn get(
        &self,
        g: &Granular,
        region: &Region,
        outer: impl IntoIterator<Item = OuterContact>,
    ) -> measure::ContactSums {
        let key = state_key(g);
        let mut m = self.0.lock().unwrap_or_else(|e| e.into_inner());
        match &*m {
            Some((k, c)) if *k == key => c.clone(),
            _ => {
                let c = measure::contact_sums(g, region, outer);
                *m = Some((key, c.clone()));
                c
            }
        }
    }
}

/// A 64-bit key of the discs' state (see [`MeasureMemo`]): the step,
/// time and rebuild count mixed with the wrapping sums of the bit patterns
/// of every position, velocity and spin component (independent sums: a
/// streaming pass, no dependency chain).
fn state_key(g: &Granular) -> u64 {
    let p = &g.particles;
    let mut acc = [0u64; 5];
    for ((x, v), w) in p.pos.iter().zip(&p.vel).zip(&p.omega) {
        acc[0] = acc[0].wrapping_add(x.x.to_bits());
        acc[1] = acc[1].wrapping_add(x.y.to_bits());
        acc[2] = acc[2].wrapping_add(v.x.to_bits());
        acc[3] = acc[3].wrapping_add(v.y.to_bits());
        acc[4] = acc[4].wrapping_add(w.to_bits());
    }
    let mut h = 0xCBF2_9CE4_8422_2325u64;
    for x in [g.step as u64, g.time.to_bits(), g.grid.rebuilds as u64]
        .into_iter()
        .chain(acc)
    {
        h = (h ^ x).wrapping_mul(0x0000_0100_0000_01B3).rotate_left(29);
    }
    h
}

/// A wall quantity: `wall_fx`, `wall_fy` (force of the discs on it),
/// `wall_x`, `wall_y` (its first end point), `wall_stress` (normal force
/// along its outward normal per length × `thickness`, compression
/// positive: [`Wall::normal_stress`]), `wall_length`.
pub fn wall_quantity(w: &Wall, q: &str, thickness: f64) -> f64 {
    match q {
        "wall_fx" => w.force.x,
        "wall_fy" => w.force.y,
        "wall_x" => w.a.x,
        "wall_stress" => w.normal_stress(thickness),
        "wall_length" => w.length(),
        _ => w.a.y,
    }
}

/// A disc quantity of scenario disc `id` (0-based): `x`, `y`, `vx`, `vy`,
/// `theta`, `omega`.
pub fn disc_quantity(gr: &Granular, id: usize, q: &str) -> f64 {
    let k = gr.slot(id);
    let p = &gr.particles;
    match q {
        "x" => p.pos[k].x,
        "y" => p.pos[k].y,
        "vx" => p.vel[k].x,
        "vy" => p.vel[k].y,
        "theta" => p.theta[k],
        _ => p.omega[k],
    }
}

/// An assembly-wide quantity (disc–disc and disc–wall contacts only for
/// `contacts`).
pub fn global_quantity(gr: &Granular, q: &str) -> f64 {
    if q == "contacts" {
        let (a, b) = gr.touching();
        return (a + b) as f64;
    }
    energy_quantity(&gr.energies(), q)
}

/// `kinetic`, `rotational`, `spring`, `gravity_energy` or (else) the
/// total of `e`.
fn energy_quantity(e: &crate::dem::Energies, q: &str) -> f64 {
    match q {
        "kinetic" => e.kinetic,
        "rotational" => e.rotational,
        "spring" => e.spring,
        "gravity_energy" => e.gravity,
        _ => e.total(),
    }
}

/// The value of `p` in a model with these parts (`body(i)`: body `i`).
pub fn value<'a>(
    p: &Probe,
    granular: Option<&Granular>,
    coupled: Option<&CoupledModel>,
    body: impl Fn(usize) -> BodyRef<'a>,
) -> f64 {
    let g = || granular.expect("a probe of the discs needs a granular assembly");
    match p {
        Probe::BodyPoint {
            body: b,
            at,
            point,
            generation,
            field,
        } => {
            let b = body(*b);
            let s = if b.generation() == *generation {
                Some(b.sample_at(at))
            } else {
                b.sample(*point).ok()
            };
            s.and_then(|s| s.field(field)).unwrap_or(f64::NAN)
        }
        Probe::Crack {
            body: b,
            crack,
            end,
            quantity,
        } => crack_quantity(body(*b), *crack, *end, quantity),
        Probe::BodyEnergy { body: b, quantity } => {
            let b = body(*b);
            match quantity.as_str() {
                "kinetic_energy" => b.kinetic_energy(),
                "strain_energy" => b.strain_energy(),
                _ => b.kinetic_energy() + b.strain_energy(),
            }
        }
        Probe::Drive {
            body: b,
            index,
            quantity,
        } => {
            let d = body(*b).drives()[*index].1;
            match &quantity[..quantity.len() - 1] {
                "drive_u" => d.d,
                "drive_v" => d.velocity,
                _ => d.measured,
            }
        }
        Probe::BodyForce { body: b, y } => coupled.map_or(0.0, |m| {
            m.contacts
                .iter()
                .filter(|c| c.body as usize == *b)
                .map(|c| if *y { -c.force.y } else { -c.force.x })
                .sum()
        }),
        Probe::Disc { id, quantity, x0 } => {
            let g = g();
            match quantity.as_str() {
                "ux" => g.particles.pos[g.slot(*id)].x - x0.x,
                "uy" => g.particles.pos[g.slot(*id)].y - x0.y,
                q => disc_quantity(g, *id, q),
            }
        }
        Probe::Contact { a, b, total } => {
            let g = g();
            let (el, tot) = g.normal_force(g.slot(*a), g.slot(*b));
            if *total { tot } else { el }
        }
        Probe::Wall { wall, quantity } => {
            let g = g();
            wall_quantity(&g.walls[*wall], quantity, g.thickness)
        }
        Probe::Measure {
            region,
            quantity,
            memo,
        } => {
            let g = g();
            if *quantity == Quantity::Porosity {
                return measure::porosity(g, region);
            }
            let outer = coupled.into_iter().flat_map(|m| {
                m.contacts.iter().map(|c| OuterContact {
                    slot: g.slot(c.disc as usize),
                    point: c.point,
                    normal: c.normal,
                    force: c.force,
                })
            });
            let sums = memo.get(g, region, outer);
            sums.finish(region, g.thickness).get(*quantity)
        }
        Probe::Global { quantity } => {
            let v = global_quantity(g(), quantity);
            match (quantity.as_str(), coupled) {
                ("contacts", Some(m)) => v + m.contacts.len() as f64,
                _ => v,
            }
        }
    }
}

/// A crack quantity ([`Probe::Crack`]) of a body; NaN where it has no
/// meaning (an FE body, an end that is a mouth, a failed integral).
fn crack_quantity(b: BodyRef<'_>, crack: usize, end: usize, q: &str) -> f64 {
    let BodyRef::Efg(b) = b else {
        return f64::NAN;
    };
    match q {
        "fracture_energy" => return b.fracture_energy,
        "crack_length" => return b.cracks().get(crack).map_or(f64::NAN, |c| c.crack.length()),
        _ => {}
    }
    let tip = crate::efg::fracture::Tip { crack, end };
    if !b.tips().contains(&tip) {
        return f64::NAN;
    }
    let Ok(k) = b.stress_intensity(tip, b.default_ring(tip)) else {
        return f64::NAN;
    };
    match q {
        "k1" => k[0],
        "k2" => k[1],
        _ => crate::continuum::crack_tip::max_hoop_stress(k).1,
    }
}

/// A probe's share of one part of a granular assembly divided over ranks
/// (`crate::decomp`): the shares of every part, [merged](Share::merge) in
/// any order, [finish] into the value the undivided assembly
/// gives, bitwise. Sums are exact ([`ExactSum`]), counts integers, and a
/// value of one disc comes from the part that owns it.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Share {
    /// Exact sums.
    pub sums: Vec<ExactSum>,
    /// Counts.
    pub counts: Vec<u64>,
    /// A value known to the part that owns its disc, or to every part (a
    /// wall's, the same on each); the first part's that has one wins.
    pub value: Option<f64>,
}

impl Share {
    /// Add the share of another part.
    pub fn merge(&mut self, o: &Share) {
        // a default share takes the shape of the first merged into it
        if self.sums.len() < o.sums.len() {
            self.sums.resize(o.sums.len(), ExactSum::default());
        }
        if self.counts.len() < o.counts.len() {
            self.counts.resize(o.counts.len(), 0);
        }
        self.sums
            .iter_mut()
            .zip(&o.sums)
            .for_each(|(a, b)| a.merge(b));
        self.counts
            .iter_mut()
            .zip(&o.counts)
            .for_each(|(a, b)| *a += b);
        self.value = self.value.or(o.value);
    }

    /// The share as `f64`s, for another process.
    pub fn pack(&self, out: &mut Vec<f64>) {
        out.push(self.sums.len() as f64);
        for s in &self.sums {
            let p = s.parts();
            out.push(p.len() as f64);
            out.extend(p);
        }
        out.push(self.counts.len() as f64);
        out.extend(self.counts.iter().map(|&c| c as f64));
        out.push(self.value.is_some() as u8 as f64);
        out.push(self.value.unwrap_or(0.0));
    }

    /// A share [packed](Self::pack) at the front of `v`; `v` moves past it.
    pub fn unpack(v: &mut &[f64]) -> Share {
        let mut take = |n: usize| {
            let (a, b) = v.split_at(n);
            *v = b;
            a
        };
        let n = take(1)[0] as usize;
        let sums = (0..n)
            .map(|_| {
                let k = take(1)[0] as usize;
                ExactSum::from_parts(take(k))
            })
            .collect();
        let n = take(1)[0] as usize;
        let counts = take(n).iter().map(|&c| c as u64).collect();
        let h = take(2);
        Share {
            sums,
            counts,
            value: (h[0] != 0.0).then_some(h[1]),
        }
    }
}

/// The share of `p` ([`Share`]) of the part `g` of a divided granular
/// assembly, its ghosts up to date and its walls' totals those of the
/// whole. `None` for a probe of a body (coupled runs are not reduced
/// this way).
pub fn share(p: &Probe, g: &Granular) -> Option<Share> {
    let ps = &g.particles;
    let owned = |id: usize| ps.own_slot(id);
    let sums = |sums: Vec<ExactSum>| Share {
        sums,
        ..Share::default()
    };
    Some(match p {
        Probe::Disc { id, quantity, x0 } => Share {
            value: owned(*id).map(|s| match quantity.as_str() {
                "ux" => ps.pos[s].x - x0.x,
                "uy" => ps.pos[s].y - x0.y,
                q => disc_quantity(g, *id, q),
            }),
            ..Share::default()
        },
        Probe::Contact { a, b, total } => Share {
            value: owned(*a).map(|sa| {
                // a partner beyond a ghost's reach touches nothing
                let sb = ps.slot.get(*b).map_or(usize::MAX, |&s| s as usize);
                let (el, tot) = if sb < ps.len() {
                    g.normal_force(sa, sb)
                } else {
                    (0.0, 0.0)
                };
                if *total { tot } else { el }
            }),
            ..Share::default()
        },
        Probe::Wall { wall, quantity } => Share {
            value: Some(wall_quantity(&g.walls[*wall], quantity, g.thickness)),
            ..Share::default()
        },
        Probe::Measure {
            region,
            quantity: Quantity::Porosity,
            ..
        } => sums(vec![measure::solid_area(g, region)]),
        Probe::Measure { region, memo, .. } => {
            let c = memo.get(g, region, []);
            Share {
                sums: c.fl.into_iter().chain(c.nn).collect(),
                counts: vec![c.contacts as u64, c.discs as u64],
                value: None,
            }
        }
        Probe::Global { quantity } if quantity == "contacts" => {
            let (a, b) = g.touching();
            Share {
                counts: vec![(a + b) as u64],
                ..Share::default()
            }
        }
        Probe::Global { .. } => sums(g.energy_sums(&ps.vel, &ps.omega).into_iter().collect()),
        _ => return None,
    })
}

/// The value of `p` from the [`Share`]s of every part merged (`g`: any
/// part, for the constants).
pub fn finish(p: &Probe, s: &Share, g: &Granular) -> f64 {
    match p {
        Probe::Measure {
            region,
            quantity: Quantity::Porosity,
            ..
        } => 1.0 - s.sums[0].value() / region.area(),
        Probe::Measure {
            region, quantity, ..
        } => {
            let c = measure::ContactSums {
                fl: std::array::from_fn(|k| s.sums[k].clone()),
                nn: std::array::from_fn(|k| s.sums[4 + k].clone()),
                contacts: s.counts[0] as usize,
                discs: s.counts[1] as usize,
            };
            c.finish(region, g.thickness).get(*quantity)
        }
        Probe::Global { .. } if !s.counts.is_empty() => s.counts[0] as f64,
        Probe::Global { quantity } => {
            let e = crate::dem::Energies::from_sums(&s.sums, g.bonds.energy(g.thickness));
            energy_quantity(&e, quantity)
        }
        _ => s.value.unwrap_or(f64::NAN),
    }
}
