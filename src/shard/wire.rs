//! What a sharded computation needs of the wire: reading a request of each kind into its case
//! (and the canonical bytes of its resolved inputs, which the parts' hash covers) and writing
//! the answer from the merged results. The service's wire implements it
//! (`http::parts::HttpWire`); `main` hands it to [`super::compute`] and [`super::merge`].

use bytes::Bytes;
use serde::Serialize;
use serde::de::DeserializeOwned;

use super::Failure;
use crate::calc::Report;
use crate::config::Config;
use crate::physics::migration::{MigrationCase, MigrationResult};
use crate::physics::scene::{EnsembleReport, SceneCase, SceneError, SceneReport};
use crate::physics::{Control, PhysicsError};

/// Reads the requests of a sharded computation and writes its answer.
pub trait Wire: Sync {
    /// A migration request as read, kept for its answer.
    type Migration;
    /// A scene request as read, with what its answer needs of it.
    type Scene: Sync;
    /// What part 0 of a scene stores: the nominal run's pieces of the answer.
    type SceneHead: Serialize + DeserializeOwned;
    /// A study's plan of points.
    type Study: Sync;
    /// One batch item as read (or its refusal).
    type Item: Sync;

    /// Reads a migration request: its case, the request, the bytes of its resolved inputs.
    ///
    /// # Errors
    /// A refused request.
    fn migration(
        &self,
        request: &[u8],
        config: &Config,
    ) -> Result<(MigrationCase, Self::Migration, Vec<u8>), Failure>;

    /// The answer's bytes of a migration's `report`.
    ///
    /// # Errors
    /// A non-finite number in the answer.
    fn migration_answer(
        &self,
        report: Report<MigrationResult>,
        req: Self::Migration,
    ) -> Result<Vec<u8>, Failure>;

    /// The failure of a migration's solver.
    fn physics_failure(&self, e: PhysicsError) -> Failure;

    /// Reads a scene request: its case, the request, the bytes of its resolved inputs.
    ///
    /// # Errors
    /// A refused request.
    fn scene(
        &self,
        request: &[u8],
        config: &Config,
    ) -> Result<(SceneCase, Self::Scene, Vec<u8>), Failure>;

    /// The failure of a scene's solver, named as the service names it.
    fn scene_failure(&self, e: SceneError, req: &Self::Scene) -> Failure;

    /// The head part 0 stores of the nominal `report` (`ensemble`: an ensemble follows).
    ///
    /// # Errors
    /// A non-finite number in a piece.
    fn scene_head(
        &self,
        report: &Report<SceneReport>,
        ensemble: bool,
        case: &SceneCase,
        req: &Self::Scene,
    ) -> Result<Self::SceneHead, Failure>;

    /// The nominal impact of `head` went past the contact capacity.
    fn nominal_capacity(head: &Self::SceneHead) -> bool;

    /// The answer lists the runs (a runs CSV): the merge keeps them.
    fn keep_runs(req: &Self::Scene) -> bool;

    /// The answer's bytes of a scene: the stored `head` with the ensemble's `tail`.
    ///
    /// # Errors
    /// A head that does not fit the tail; a non-finite number in the tail.
    fn scene_answer(
        &self,
        head: Self::SceneHead,
        tail: Option<EnsembleReport>,
        case: &SceneCase,
        req: Self::Scene,
    ) -> Result<Vec<u8>, Failure>;

    /// Reads a study request: its plan and the bytes of its resolved inputs.
    ///
    /// # Errors
    /// A refused request.
    fn study(&self, request: &[u8], config: &Config) -> Result<(Self::Study, Vec<u8>), Failure>;

    /// The number of points of `plan`, its base point included.
    fn study_points(plan: &Self::Study) -> u64;

    /// The outputs of point `index` of `plan`.
    ///
    /// # Errors
    /// A point whose solver fails.
    fn study_point(
        &self,
        plan: &Self::Study,
        config: &Config,
        index: usize,
        control: &Control,
    ) -> Result<Vec<f64>, Failure>;

    /// The answer's bytes of a study from the outputs of all its points, in order.
    ///
    /// # Errors
    /// A non-finite number in the answer.
    fn study_answer(&self, plan: Self::Study, results: Vec<Vec<f64>>) -> Result<Vec<u8>, Failure>;

    /// Reads a batch (a JSON envelope or NDJSON): its items and the bytes of its inputs.
    ///
    /// # Errors
    /// A refused batch (too many items, a damaged envelope).
    fn batch(&self, request: &[u8], config: &Config)
    -> Result<(Vec<Self::Item>, Vec<u8>), Failure>;

    /// The answer line of batch item `index` (a refusal or a panic is a line too).
    fn batch_line(
        &self,
        index: usize,
        item: &Self::Item,
        config: &Config,
        control: &Control,
    ) -> Bytes;
}
