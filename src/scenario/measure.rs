//! `[[measure]]`: stress, porosity, coordination number and fabric of the
//! discs in a region ([`crate::dem::measure`]), as `history.csv` columns
//! `<name>_sxx_cpos`, `<name>_syy_cpos`, … (stresses compression
//! positive, as the names say) — one bound [`Probe::Measure`] per column,
//! so that every driver records them as it records the probes; the columns
//! of one region share one pass over the contacts per state
//! ([`MeasureMemo`]).
//!
//! ```toml
//! [[measure]]
//! name = "core"
//! rectangle = [[0.05, 0.05], [0.25, 0.25]]    # or centre = [x, y], radius = r
//! quantities = ["sxx_cpos", "syy_cpos", "porosity"]   # default: all eight
//! ```

use super::{Invalid, Problems, Scenario};
use crate::dem::measure::{Quantity, Region};
use crate::geom::Vec2;
use crate::model::probe::MeasureMemo;
use crate::model::{Model, Probe};
use serde::Deserialize;

/// A measurement region.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MeasureSpec {
    /// Prefix of the history columns: `<name>_sxx_cpos`, ….
    pub name: String,
    /// `[[x0, y0], [x1, y1]]` (or `{ origin, size }`, [`super::rect`]): a
    /// rectangle …
    #[serde(default, deserialize_with = "super::rect::corners")]
    pub rectangle: Option<[[f64; 2]; 2]>,
    /// … or the centre of a circle (`center` is the same field) …
    #[serde(alias = "center")]
    pub centre: Option<[f64; 2]>,
    /// … and its radius.
    pub radius: Option<f64>,
    /// The columns to write (default: every quantity, in the order of
    /// [`Quantity::ALL`]).
    pub quantities: Option<Vec<String>>,
}

impl MeasureSpec {
    /// The region (after validation).
    pub fn region(&self) -> Option<Region> {
        match (self.rectangle, self.centre, self.radius) {
            (Some([a, b]), None, None) => Some(Region::Rectangle {
                lo: Vec2::from(a),
                hi: Vec2::from(b),
            }),
            (None, Some(c), Some(r)) => Some(Region::Circle {
                centre: Vec2::from(c),
                radius: r,
            }),
            _ => None,
        }
    }

    /// The quantities of its columns, in order (unknown names dropped: the
    /// validation reports them).
    pub fn quantities(&self) -> Vec<Quantity> {
        match &self.quantities {
            None => Quantity::ALL.to_vec(),
            Some(v) => v.iter().filter_map(|q| Quantity::from_name(q)).collect(),
        }
    }

    /// Its history column names, `<name>_<quantity>`.
    pub fn columns(&self) -> Vec<String> {
        self.quantities()
            .iter()
            .map(|q| format!("{}_{}", self.name, q.name()))
            .collect()
    }
}

/// Semantic checks of every `[[measure]]`.
pub fn validate(sc: &Scenario, p: &mut Problems) {
    if sc.measure.is_empty() {
        return;
    }
    if sc.granular.is_none() {
        p.push("measure", "a [[measure]] needs discs ([granular])");
        return;
    }
    let mut columns: std::collections::HashSet<String> =
        sc.probe.iter().map(|pr| pr.name.clone()).collect();
    for (i, m) in sc.measure.iter().enumerate() {
        let at = |f: &str| format!("measure.{i}.{f}");
        p.check(!m.name.is_empty(), at("name"), "must not be empty");
        let finite = |v: &[f64]| v.iter().all(|x| x.is_finite());
        match (m.rectangle, m.centre, m.radius) {
            (Some([a, b]), None, None) => p.check(
                finite(&a) && finite(&b) && b[0] > a[0] && b[1] > a[1],
                at("rectangle"),
                "must be [[x0, y0], [x1, y1]] with x1 > x0 and y1 > y0",
            ),
            (None, Some(c), Some(r)) => {
                p.check(finite(&c), at("centre"), "must be two finite numbers");
                p.positive(r, at("radius"));
            }
            (None, Some(_), None) => p.push(at("centre"), "a circle needs `radius` too"),
            (None, None, Some(_)) => p.push(at("radius"), "a circle needs `centre` too"),
            (None, None, None) => p.push(
                at("name"),
                "needs a region: `rectangle = [[x0, y0], [x1, y1]]` or `centre = [x, y]` with `radius = r`",
            ),
            _ => p.push(
                at("rectangle"),
                "give either `rectangle` or `centre` and `radius`, not both",
            ),
        }
        if let Some(qs) = &m.quantities {
            p.check(!qs.is_empty(), at("quantities"), "must not be empty");
            let mut seen = std::collections::HashSet::new();
            for (k, q) in qs.iter().enumerate() {
                let renamed = ["sxx", "syy", "sxy"].contains(&q.as_str());
                p.check(
                    Quantity::from_name(q).is_some(),
                    format!("measure.{i}.quantities.{k}"),
                    match renamed {
                        true => format!(
                            "`{q}` is now `{q}_cpos`: the same compression-positive stress, named by its sign (a body's `{q}` probe is tension positive)"
                        ),
                        false => format!(
                            "unknown quantity `{q}` (allowed: {})",
                            Quantity::ALL.map(Quantity::name).join(", ")
                        ),
                    },
                );
                p.check(
                    seen.insert(q.as_str()),
                    format!("measure.{i}.quantities.{k}"),
                    format!("`{q}` is listed twice"),
                );
            }
        }
        for c in m.columns() {
            if !columns.insert(c.clone()) {
                p.push(
                    at("name"),
                    format!("its column `{c}` is already a probe or another measure's column"),
                );
                break;
            }
        }
    }
}

/// The bound probes of every `[[measure]]`, one per column, in file order.
pub fn probes(sc: &Scenario, model: &Model) -> Result<Vec<(String, Probe)>, Invalid> {
    if !sc.measure.is_empty() && model.granular().is_none() {
        return Err(Invalid {
            path: "measure".into(),
            message: "a [[measure]] needs discs ([granular])".into(),
        });
    }
    let mut out = Vec::new();
    for (i, m) in sc.measure.iter().enumerate() {
        let region = m.region().ok_or_else(|| Invalid {
            path: format!("measure.{i}.name"),
            message: "needs one region".into(),
        })?;
        let memo = std::sync::Arc::new(MeasureMemo::default());
        for (q, name) in m.quantities().into_iter().zip(m.columns()) {
            out.push((
                name,
                Probe::Measure {
                    region,
                    quantity: q,
                    memo: memo.clone(),
                },
            ));
        }
    }
    Ok(out)
}
