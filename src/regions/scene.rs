//! `W` of a scene at its initial state: the contact the map is drawn for.

use crate::contact::{PairContact, pair_contact};
use crate::impact::{ContactVelocity, ImpactMatrix};
use crate::kinematics::update_positions;
use crate::math::Real;
use crate::model::{ColliderId, Material, Model, PairId};
use crate::sim::{ImpactMap, SimError};
use crate::state::{Data, State};

/// The contact of a scene the map is drawn for, at the scene's initial state.
#[derive(Clone, Debug, PartialEq)]
pub struct SceneContact {
    /// The pair.
    pub pair: PairId,
    /// Its name, `a/b` (the colliders' names, as in the impact table of `ricochet run`).
    pub name: String,
    /// Signed gap at the initial state (m).
    pub gap: Real,
    /// `W = J M⁻¹ Jᵀ` at the pair's contact point [P, Eq. (20)], tangent along the slip
    /// (`t = perp(n)` when there is none).
    pub w: ImpactMatrix,
    /// The relative velocity there (m/s): `α = v_t / |v_n|` is the scene's own point on
    /// the map when `v_n < 0`.
    pub v: ContactVelocity,
    /// The pair's material (law, `e`, `μ`).
    pub material: Material,
}

impl SceneContact {
    /// `α = v_t / |v_n|` [P, Eq. (34)] if the contact approaches (`v_n < 0`).
    pub fn alpha(&self) -> Option<Real> {
        (self.v.n < 0.0).then(|| self.v.t / -self.v.n)
    }
}

/// The name of a pair, `a/b` (its colliders' names, as in the impact table of `ricochet run`).
pub fn pair_name(model: &Model, pair: PairId) -> String {
    let p = &model.pair_of(pair);
    let name = |c: ColliderId| model.colliders()[c.index()].name.as_str();
    format!("{}/{}", name(p.a), name(p.b))
}

/// The contact of the pair named `pair` (`a/b`, or its index from 0), or for `None` of
/// the pair with the smallest signed gap (the first one on a tie), at the state `state`,
/// with its `W` computed by the simulator's own impact map ([`ImpactMap::impact_matrix`]).
///
/// Errors: the model has no contact pair, no pair is named `pair` (the message lists
/// them), or the kinematics, contact query or mass matrix fail.
pub fn scene_contact(
    model: &Model,
    state: &State,
    pair: Option<&str>,
) -> Result<SceneContact, SimError> {
    let (t, q, u) = (state.t, state.q.as_slice(), state.u.as_slice());
    // The pairs in order: `pair` names one, or gives its rank among them from 0.
    let ids: Vec<PairId> = model.pair_ids().collect();
    let names: Vec<String> = ids.iter().map(|&id| pair_name(model, id)).collect();
    let chosen = |k: usize| pair.is_none_or(|p| p == names[k] || p.parse() == Ok(k));
    let mut data = Data::new(model);
    update_positions(model, &mut data, t, q).map_err(|e| SimError::at(t, e))?;
    let mut best: Option<(usize, PairContact)> = None;
    for k in (0..ids.len()).filter(|&k| chosen(k)) {
        let contact =
            pair_contact(model, &data, ids[k], Real::INFINITY).map_err(|e| SimError::at(t, e))?;
        if let Some(c) = contact
            && best.is_none_or(|(_, b)| c.gap < b.gap)
        {
            best = Some((k, c));
        }
    }
    let Some((k, contact)) = best else {
        let message = match pair {
            None => "the scene has no contact pair".to_owned(),
            Some(p) => format!(
                "no contact pair `{p}`; the pairs are: {}",
                if names.is_empty() {
                    "none".to_owned()
                } else {
                    names.join(", ")
                }
            ),
        };
        return Err(SimError::Contact { t, message });
    };
    let id = ids[k];
    let (frame, w) = ImpactMap::new(model).impact_matrix(model, (id, contact), t, q, u)?;
    Ok(SceneContact {
        pair: id,
        name: names[k].clone(),
        gap: contact.gap,
        w,
        v: ContactVelocity::new(frame.v_n(), frame.v_t()),
        material: model.pair_of(id).material,
    })
}
