//! Design objectives: every kind's analytic gradient against central finite
//! differences at random states (fixed seed), the dexterity guard at
//! singular poses, reported values against closed forms, and the errors of
//! bad objective entries.

mod common;
mod errors;
mod gradients;
mod values;
