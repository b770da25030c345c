//! The finger targets after a host stall: caught up at a bounded speed.
//!
//! After skipped grid slots the devices are read at grid time, so each
//! fingertip has moved a whole gap's worth of hand motion since the last
//! tick, while the world steps one period (`fast::MAX_SIMULATED_PERIODS`).
//! Handed over at once, that jump is a hand moving n times its speed for
//! one tick: the coupling's rate term, a proxy's velocity in Eq. 7 and the
//! bodies it pushes all see it (BENCHMARKS.md, "Contact: missed ticks").
//! Instead, the target the program sees moves per simulated period at most
//! the hand's own motion plus a catch-up of the hand's mean speed over the
//! gap, so the world sees the hand at most twice as fast as it moved and the
//! lag closes within about as many ticks as the gap had periods. The
//! orientation (a rigid grasp's) is caught up the same way, by angle,
//! independently of the position. Without a gap the targets pass unchanged
//! (bit for bit).

use haptloop_solver::FingerTarget;

/// Per finger: what the program was given and how fast it may catch up.
#[derive(Debug, Clone)]
pub(super) struct TargetCatchUp {
    /// The target handed to the program last tick.
    shown: Vec<FingerTarget>,
    /// The device's target last tick.
    raw_prev: Vec<FingerTarget>,
    /// Catch-up per simulated period, m (0: not lagging).
    catch_up_m: Vec<f64>,
    /// The same for the orientation, rad.
    catch_up_rad: Vec<f64>,
    started: bool,
}

impl TargetCatchUp {
    /// For `fingers` fingers (allocates).
    pub(super) fn new(fingers: usize) -> Self {
        let zero = FingerTarget::at(nalgebra::Vector3::zeros());
        TargetCatchUp {
            shown: vec![zero; fingers],
            raw_prev: vec![zero; fingers],
            catch_up_m: vec![0.0; fingers],
            catch_up_rad: vec![0.0; fingers],
            started: false,
        }
    }

    /// Replaces `targets` (the devices' targets this tick, `gap` periods
    /// after the last tick, of which the world simulates `simulated`) by
    /// the targets the program may see. Returns the largest distance left
    /// between a device's target and the one given, m (0 when none lags).
    ///
    /// # Real-time
    /// No allocation; O(fingers).
    pub(super) fn apply(&mut self, targets: &mut [FingerTarget], gap: u64, simulated: u64) -> f64 {
        if !self.started || self.shown.len() != targets.len() {
            self.started = self.shown.len() == targets.len();
            self.shown.copy_from_slice(targets);
            self.raw_prev.copy_from_slice(targets);
            return 0.0;
        }
        let gap = gap.max(1) as f64;
        let simulated = simulated.max(1) as f64;
        let mut lag_max: f64 = 0.0;
        for (i, t) in targets.iter_mut().enumerate() {
            let (raw, prev) = (*t, self.raw_prev[i]);
            self.raw_prev[i] = raw;
            let lag = self.position(i, &raw, &prev, gap, simulated);
            self.orientation(i, &raw, &prev, gap, simulated);
            lag_max = lag_max.max(lag);
            *t = self.shown[i];
        }
        lag_max
    }

    /// Moves finger `i`'s shown position towards the device's; returns the
    /// distance left, m.
    fn position(
        &mut self,
        i: usize,
        raw: &FingerTarget,
        prev: &FingerTarget,
        gap: f64,
        simulated: f64,
    ) -> f64 {
        let per_period = (raw.position_m - prev.position_m).norm() / gap;
        if gap > simulated {
            self.catch_up_m[i] = self.catch_up_m[i].max(per_period);
        }
        let allowed = (per_period + self.catch_up_m[i]) * simulated;
        let d = raw.position_m - self.shown[i].position_m;
        let dist = d.norm();
        if dist <= allowed || !dist.is_finite() {
            self.shown[i].position_m = raw.position_m;
            self.catch_up_m[i] = 0.0;
            return 0.0;
        }
        self.shown[i].position_m += d * (allowed / dist);
        dist - allowed
    }

    /// The same for the orientation, by angle.
    fn orientation(
        &mut self,
        i: usize,
        raw: &FingerTarget,
        prev: &FingerTarget,
        gap: f64,
        simulated: f64,
    ) {
        let per_period = prev.orientation.angle_to(&raw.orientation) / gap;
        if gap > simulated {
            self.catch_up_rad[i] = self.catch_up_rad[i].max(per_period);
        }
        let allowed = (per_period + self.catch_up_rad[i]) * simulated;
        let shown = &mut self.shown[i].orientation;
        let angle = shown.angle_to(&raw.orientation);
        if angle <= allowed || !angle.is_finite() {
            *shown = raw.orientation;
            self.catch_up_rad[i] = 0.0;
            return;
        }
        *shown = shown
            .try_slerp(&raw.orientation, allowed / angle, 1e-9)
            .unwrap_or(raw.orientation);
    }
}

#[cfg(test)]
mod tests {
    use super::TargetCatchUp;
    use haptloop_solver::FingerTarget;
    use nalgebra::Vector3;

    fn at(x: f64) -> FingerTarget {
        FingerTarget::at(Vector3::new(x, 0.0, 0.0))
    }

    /// A hand at 1 mm a period, a 10-period gap: the target moves 2 mm a
    /// tick until it has caught up, and no target passes the device's.
    #[test]
    fn a_gap_is_caught_up_at_twice_the_hands_speed() {
        let mut c = TargetCatchUp::new(1);
        let mut x = 0.0;
        let mut t = [at(x)];
        c.apply(&mut t, 1, 1);
        for _ in 0..3 {
            x += 1e-3;
            t = [at(x)];
            assert_eq!(c.apply(&mut t, 1, 1), 0.0);
            assert_eq!(t[0].position_m.x, x, "no gap: unchanged");
        }
        x += 10e-3;
        t = [at(x)];
        let lag = c.apply(&mut t, 10, 1);
        let mut shown = t[0].position_m.x;
        assert!((x - shown - 8e-3).abs() < 1e-12, "{shown}");
        assert!((lag - 8e-3).abs() < 1e-12);
        let mut ticks = 0;
        while shown < x - 1e-15 || ticks == 0 {
            x += 1e-3;
            t = [at(x)];
            c.apply(&mut t, 1, 1);
            let step = t[0].position_m.x - shown;
            assert!(step <= 2e-3 + 1e-12 && t[0].position_m.x <= x, "{step}");
            shown = t[0].position_m.x;
            ticks += 1;
        }
        assert_eq!(ticks, 8, "8 mm of lag closes at 1 mm a tick");
    }

    /// A hand turning 0.01 rad a period about z with its position still,
    /// a 10-period gap: the orientation is caught up at twice the hand's
    /// angular speed (0.02 rad a tick), never past the device's, and the
    /// position stays where it is.
    #[test]
    fn an_orientation_is_caught_up_at_twice_the_hands_angular_speed() {
        let turn = |a: f64| FingerTarget {
            position_m: Vector3::new(0.1, 0.0, 0.0),
            orientation: nalgebra::UnitQuaternion::from_axis_angle(&Vector3::z_axis(), a),
        };
        let mut c = TargetCatchUp::new(1);
        let mut a = 0.0;
        let mut t = [turn(a)];
        c.apply(&mut t, 1, 1);
        a += 0.01;
        t = [turn(a)];
        c.apply(&mut t, 1, 1);
        assert_eq!(t[0].orientation, turn(a).orientation, "no gap: unchanged");
        let mut shown = a;
        a += 0.10;
        t = [turn(a)];
        assert_eq!(c.apply(&mut t, 10, 1), 0.0, "the position does not lag");
        let angle = |t: &FingerTarget| t.orientation.angle();
        assert!(
            (angle(&t[0]) - shown - 0.02).abs() < 1e-12,
            "{}",
            angle(&t[0])
        );
        shown = angle(&t[0]);
        let mut ticks = 1;
        while shown < a - 1e-12 {
            a += 0.01;
            t = [turn(a)];
            c.apply(&mut t, 1, 1);
            let step = angle(&t[0]) - shown;
            assert!(step <= 0.02 + 1e-12 && angle(&t[0]) <= a + 1e-12, "{step}");
            assert_eq!(t[0].position_m, turn(a).position_m);
            shown = angle(&t[0]);
            ticks += 1;
        }
        assert_eq!(ticks, 9, "0.09 rad of lag closes at 0.01 rad a tick");
    }
}
