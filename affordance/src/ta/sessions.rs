//! Registration of sessions onto a reference map (seed 002, §4.4).

use haunts_occupancy::{OccupancyGrid, Pose2};
use haunts_similarity::{GlobalMatch, GlobalParams, register_maps};
use haunts_tracking::Trajectory;

use crate::Result;

/// One data-collection session: its occupancy map and its (filtered) trajectories, both in
/// the session's own map frame.
#[derive(Debug, Clone, PartialEq)]
pub struct Session {
    /// The session's occupancy map.
    pub map: OccupancyGrid,
    /// Its trajectories, in the map's frame.
    pub trajectories: Vec<Trajectory>,
}

/// A session moved into the reference frame.
#[derive(Debug, Clone, PartialEq)]
pub struct RegisteredSession {
    /// The registration: `pose` is the session frame's pose in the reference frame.
    pub registration: GlobalMatch,
    /// The session's trajectories in the reference frame (times unchanged).
    pub trajectories: Vec<Trajectory>,
}

/// Registers `session`'s map onto `reference` with the similarity crate's global
/// registration (Harris corners, ring descriptors, RANSAC + Umeyama, ICP; no initial guess)
/// and moves its trajectories into the reference frame: `p_ref = pose · p` (seed 002,
/// Eq. 12).
///
/// # Errors
/// [`AffordanceError::Similarity`](crate::AffordanceError::Similarity) from
/// [`register_maps`]: `NoReliableMatch` when the maps do not match (never a wrong transform
/// knowingly returned), `EmptyMap`, `ResolutionMismatch`, bad parameters.
pub fn register_session(
    reference: &OccupancyGrid,
    session: &Session,
    params: &GlobalParams,
) -> Result<RegisteredSession> {
    let registration = register_maps(reference, &session.map, params)?;
    Ok(RegisteredSession {
        trajectories: transform(&session.trajectories, &registration.pose),
        registration,
    })
}

/// The trajectories with every position mapped by `pose`.
fn transform(trajectories: &[Trajectory], pose: &Pose2) -> Vec<Trajectory> {
    trajectories
        .iter()
        .map(|t| Trajectory {
            id: t.id,
            samples: t
                .samples
                .iter()
                .map(|&(time, p)| (time, pose * p))
                .collect(),
        })
        .collect()
}
