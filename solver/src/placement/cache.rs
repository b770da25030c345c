//! [`PlacementCache`]: analyses kept by [`StructureKey`], so a contact set that
//! changes and changes back, or a scene reloaded with the same joints, reuses
//! its symbolic analysis instead of redoing it.

use super::{Placement, PlacementError, PlacementOptions, StructureKey};
use crate::Model;

/// A small least-recently-used set of [`Placement`]s, one per structure, all
/// analysed with the same options. Slow thread only (analysis allocates).
#[derive(Debug)]
pub struct PlacementCache {
    options: PlacementOptions,
    capacity: usize,
    /// Most recently used last.
    entries: Vec<Placement>,
    analyses: u64,
}

impl PlacementCache {
    /// An empty cache keeping at most `capacity` (≥ 1) analyses.
    pub fn new(options: PlacementOptions, capacity: usize) -> Self {
        Self {
            options,
            capacity: capacity.max(1),
            entries: Vec::new(),
            analyses: 0,
        }
    }

    /// The analysis for `model`'s structure: found by key, or analysed now
    /// (evicting the least recently used one when full).
    pub fn get(&mut self, model: &Model) -> Result<&mut Placement, PlacementError> {
        let key = StructureKey::of(model);
        let found = self.entries.iter().position(|p| {
            p.structure_key() == key && p.n == model.n_coords() && p.m == model.n_rows()
        });
        let placement = match found {
            Some(i) => self.entries.remove(i),
            None => {
                let p = Placement::analyze(model, &self.options)?;
                self.analyses += 1;
                if self.entries.len() >= self.capacity {
                    self.entries.remove(0);
                }
                p
            }
        };
        self.entries.push(placement);
        let last = self.entries.len() - 1;
        Ok(&mut self.entries[last])
    }

    /// Whether an analysis of `model`'s structure is held.
    pub fn contains(&self, model: &Model) -> bool {
        let key = StructureKey::of(model);
        self.entries.iter().any(|p| p.structure_key() == key)
    }

    /// Symbolic analyses performed so far (cache misses).
    pub fn analyses(&self) -> u64 {
        self.analyses
    }

    /// Analyses held.
    pub fn len(&self) -> usize {
        self.entries.len()
    }

    /// True when nothing is held.
    pub fn is_empty(&self) -> bool {
        self.entries.is_empty()
    }
}
