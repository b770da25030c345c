//! [`Pointer`]: where a person's mouse wants a [`crate::VirtualDevice`]'s
//! tip to be, shared between the thread that hears the mouse (the live
//! viewer) and the fast loop that reads the device.
//!
//! One `AtomicU64` holds the whole target: three signed 21-bit components in
//! micrometres (±1.048 m, device frame) and a "set" bit. A store and a load
//! are single atomic operations, so the reader can never see half of one
//! move and half of another, and neither side waits for the other.
//!
//! # Real-time
//! [`Pointer::get`] is one atomic load and a few shifts: no allocation, no
//! lock, constant time. [`Pointer::set`] is the same on the writer's side.

use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};

use nalgebra::Vector3;

/// Metres per unit of a stored component: 1 µm.
pub const POINTER_RESOLUTION_M: f64 = 1e-6;
/// Largest stored component magnitude, units (2²⁰ − 1).
const LIMIT: i64 = (1 << 20) - 1;
/// Largest stored component magnitude, metres (1.048575 m).
pub const POINTER_RANGE_M: f64 = LIMIT as f64 * POINTER_RESOLUTION_M;
const MASK: u64 = (1 << 21) - 1;
const SET: u64 = 1 << 63;

/// A shared, lock-free pointer target (see the [module docs](self)). Clones
/// share the same cell.
#[derive(Debug, Clone, Default)]
pub struct Pointer {
    bits: Arc<AtomicU64>,
}

impl Pointer {
    /// A pointer that has not been set (the device stays where it started).
    pub fn new() -> Self {
        Self::default()
    }

    /// Moves the target to `target_m_device` (metres, device frame), rounded
    /// to 1 µm and clamped to ±[`POINTER_RANGE_M`] per axis; a non-finite
    /// component leaves the target where it was and returns false.
    pub fn set(&self, target_m_device: &Vector3<f64>) -> bool {
        if !target_m_device.iter().all(|v| v.is_finite()) {
            return false;
        }
        let mut bits = SET;
        for (k, v) in target_m_device.iter().enumerate() {
            let units = ((v / POINTER_RESOLUTION_M).round() as i64).clamp(-LIMIT, LIMIT);
            bits |= ((units as u64) & MASK) << (21 * k);
        }
        self.bits.store(bits, Ordering::Release);
        true
    }

    /// The target, metres, device frame (`None` until the first `set`).
    ///
    /// # Real-time
    /// One atomic load; no allocation.
    pub fn get(&self) -> Option<Vector3<f64>> {
        let bits = self.bits.load(Ordering::Acquire);
        if bits & SET == 0 {
            return None;
        }
        let component = |k: usize| {
            let raw = (bits >> (21 * k)) & MASK;
            // Sign-extend the 21-bit two's complement value.
            (((raw << 43) as i64) >> 43) as f64 * POINTER_RESOLUTION_M
        };
        Some(Vector3::new(component(0), component(1), component(2)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_target_comes_back_to_the_micrometre_with_its_signs() {
        let p = Pointer::new();
        assert_eq!(p.get(), None);
        let shared = p.clone();
        for t in [
            Vector3::new(0.0123454, -0.2, 0.999_999),
            Vector3::new(-1e-6, 0.0, -0.5),
        ] {
            assert!(shared.set(&t));
            let back = p.get().unwrap();
            for k in 0..3 {
                assert!(
                    (back[k] - t[k]).abs() <= 0.5e-6 + 1e-12,
                    "{k}: {back:?} vs {t:?}"
                );
            }
        }
        // Out of range: clamped to the range, sign kept; NaN: ignored.
        assert!(p.set(&Vector3::new(5.0, -5.0, 0.0)));
        let back = p.get().unwrap();
        assert_eq!((back.x, back.y), (POINTER_RANGE_M, -POINTER_RANGE_M));
        assert!(!p.set(&Vector3::new(f64::NAN, 0.0, 0.0)));
        assert_eq!(p.get().unwrap(), back);
    }
}
