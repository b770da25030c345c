//! The tick's time per stage in `summary.json` (`session::timing`).

use crate::session::{Stage, StageTimes};
use haptloop_rt::probe::Percentiles;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// The tick's time per stage (`session::timing`), monotonic clock, ns.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Stages {
    /// The whole tick.
    pub tick: Percentiles,
    /// The tick without the device stages (device read, safety + write).
    pub tick_without_device: Percentiles,
    /// Mean of `tick_without_device`.
    pub tick_without_device_mean: f64,
    /// Per stage, by its key (`handover`, `device_read`, `update`,
    /// `evaluation`, `force`, `safety_write`, `bookkeeping`).
    pub stages: BTreeMap<String, Percentiles>,
}

impl Stages {
    /// Percentiles of `times`.
    pub fn of(times: &StageTimes) -> Stages {
        Stages {
            tick: times.tick.summary().into(),
            tick_without_device: times.tick_without_device.summary().into(),
            tick_without_device_mean: times.tick_without_device.summary().mean,
            stages: Stage::ALL
                .iter()
                .map(|&s| (s.key().to_string(), times.stage(s).summary().into()))
                .collect(),
        }
    }

    /// The percentiles of `stage`.
    pub fn get(&self, stage: Stage) -> Percentiles {
        self.stages[stage.key()]
    }
}
