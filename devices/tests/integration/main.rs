//! Integration tests of haptloop-devices: one binary, a module per area.

mod common;
mod faults;
mod multi_device;
mod passivity;
mod replay;
mod safety;
mod sim;
