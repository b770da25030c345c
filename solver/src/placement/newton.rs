//! The Newton-KKT loop of [`Placement::solve`]: damped steps, backtracking on
//! a two-part merit, adaptive (Levenberg–Marquardt) damping, the outcome.
//!
//! Acceptance of a trial x + αδ (a simple filter): the constraint residual
//! θ = ‖g‖₂ drops by the Armijo fraction 1e-4·α, **or** θ stays below
//! θ_ok = 10·tolerance while the objective f = ½‖q − q_ref‖²_W decreases
//! (tangential progress on the constraint manifold, which ‖g‖ alone would
//! reject). Up to six halvings of α; if none is accepted the damping μ grows
//! ×10 and the step is recomputed; a full step resets μ to
//! clamp(θ², 1e-4·`damping`, `damping`). μ beyond `MU_MAX` ends the solve. A failed Cholesky
//! pivot also raises μ (×100).
//!
//! Least-squares mode: when θ stalls above θ_ok for three accepted steps
//! (Newton would have contracted it), or J can no longer reduce a large
//! residual, the rows conflict. Steps are then plain Levenberg–Marquardt on
//! ψ = ½θ² + μf (gain ratio, no backtracking; `least_squares.rs`), whose
//! stationary point is the finite compromise reported as
//! [`SolveStatus::LeastSquares`] (λ = g/μ there).

use super::least_squares::lm_update;
use super::line_search::Merit;
use super::options::Knobs;
use super::step::H_MIN;
use super::{IterationRecord, Placement, PlacementError, SolveInfo, SolveStatus};
use crate::{FingerTarget, Model, RowUnit};

/// Damping beyond which a solve gives up (the step would be ~1e-4 of Newton's).
const MU_MAX: f64 = 1e4;

/// Slack below which an inequality row counts as active.
const Y_FLOOR: f64 = 1e-6;
/// A row with Y < `Y_FLOOR` and λ above this pulls (wrong sign): it is
/// released by resetting Y to `Y_FLOOR` (Y = 0 is a fixed point of δY).
const LAMBDA_PULL: f64 = 1e-10;
/// ‖Jᵀg‖ ≤ this · ‖J‖_max · ‖g‖ · √n marks a least-squares stationary point.
pub(super) const LS_GRADIENT: f64 = 1e-4;
/// Least-squares mode also starts when θ > this × tolerance and
/// ‖Jᵀg‖ ≤ `LS_ENTRY_GRADIENT` · ‖J‖_max · ‖g‖ · √n: the residual lies
/// (almost) in the left null space of J, where no step can reduce it.
const LS_ENTRY: f64 = 1e3;
const LS_ENTRY_GRADIENT: f64 = 1e-3;

/// θ above this × the previous θ counts as a stalled iteration.
const STAGNATION: f64 = 0.9;
/// Stalled iterations in a row that switch to least-squares mode.
const STAGNANT_STEPS: u32 = 3;

/// The smallest damping at residual θ: θ², between 1e-4·μ₀ and μ₀.
fn damping_floor(theta: f64, mu0: f64) -> f64 {
    (theta * theta).clamp(MU_FLOOR_RATIO * mu0, mu0)
}

/// Lowest damping relative to `options.damping` (1e-12 by default: four
/// orders above rounding in a unit-scale J Jᵀ; the bias μ|λ| it leaves is far
/// below the tolerance).
const MU_FLOOR_RATIO: f64 = 1e-6;

fn norm2(v: &[f64]) -> f64 {
    v.iter().map(|x| x * x).sum::<f64>().sqrt()
}

fn norm_inf(v: &[f64]) -> f64 {
    v.iter().fold(0.0, |m, x| m.max(x.abs()))
}

/// Where the Newton-KKT iteration stands.
struct Iterate {
    /// θ = ‖g‖₂ and f at the current iterate.
    theta: f64,
    f: f64,
    /// θ below which a trial may trade θ for f (10 × tolerance).
    theta_ok: f64,
    /// Newton's damping μ and least squares' ν.
    mu: f64,
    nu: f64,
    /// Whether any step needed extra damping.
    regularised: bool,
    status: SolveStatus,
    /// The last step's size (‖δq‖∞, slacks included).
    step: f64,
    iterations: u32,
    /// In least-squares mode (the rows conflict).
    least_squares: bool,
    /// Stalled iterations in a row.
    stagnant: u32,
}

impl Iterate {
    /// The damping in force: μ₀ + ν in least-squares mode, else μ.
    fn damping(&self, opt: &Knobs) -> f64 {
        if self.least_squares {
            opt.damping + self.nu
        } else {
            self.mu
        }
    }
}

impl Placement {
    /// Numeric phase: places `q` (start in, result out) by Newton-KKT on
    /// min ½‖q − q_ref‖²_W s.t. C_eq = 0, C_in ≥ 0, with the fingers at
    /// `targets`. Numerical outcomes, good or bad, are `Ok(SolveInfo)` with a
    /// finite q; `Err` only for inputs that cannot be solved (another
    /// structure, wrong lengths, a start that cannot be evaluated), and then q
    /// is untouched.
    ///
    /// Allocates nothing per iteration (one [`Evaluation`](crate::Evaluation)
    /// when `model` is a new object of the analysed structure). Slow thread:
    /// the time is bounded by `max_iterations` × (7 evaluations + up to 5
    /// factorisations), not by a deadline.
    pub fn solve(
        &mut self,
        model: &Model,
        q: &mut [f64],
        q_ref: &[f64],
        targets: &[FingerTarget],
    ) -> Result<SolveInfo, PlacementError> {
        self.begin(model, q, q_ref, targets)?;
        let opt = self.options.clone_scalars();
        let mut it = Iterate {
            theta: norm2(&self.g),
            f: self.objective(q, q_ref),
            theta_ok: 10.0 * opt.tolerance,
            mu: opt.damping,
            nu: 0.0,
            regularised: false,
            status: SolveStatus::MaxIterations,
            step: 0.0,
            iterations: 0,
            least_squares: false,
            stagnant: 0,
        };
        while it.iterations < opt.max_iterations {
            let Some(alpha) = self.accepted_step(model, q, q_ref, targets, &opt, &mut it) else {
                break;
            };
            self.commit(model, q, targets);
            let theta_prev = it.theta;
            it.theta = norm2(&self.g);
            it.f = self.objective(q, q_ref);
            it.iterations += 1;
            self.history.push(IterationRecord {
                residual: it.theta,
                step: it.step,
                alpha,
                damping: it.damping(&opt),
            });
            if self.judge(&opt, &mut it, alpha, theta_prev) {
                break;
            }
        }
        if it.status == SolveStatus::MaxIterations
            && it.least_squares
            && self.gradient_ratio() <= LS_GRADIENT
        {
            it.status = SolveStatus::LeastSquares;
        }
        // A rejected trial left its values in the evaluation: restore q's.
        let _ = self.eval.evaluate(model, q, targets);
        self.update_residual();
        let damping = it.damping(&opt);
        Ok(self.info(
            model,
            it.status,
            it.iterations,
            it.step,
            it.regularised,
            damping,
        ))
    }

    /// Checks the lengths and `q_ref`, evaluates C at the start and sets
    /// the slacks, multipliers and history for a new solve.
    fn begin(
        &mut self,
        model: &Model,
        q: &[f64],
        q_ref: &[f64],
        targets: &[FingerTarget],
    ) -> Result<(), PlacementError> {
        self.bind(model)?;
        for v in [q.len(), q_ref.len()] {
            if v != self.n {
                let (expected, got) = (self.n, v);
                return Err(PlacementError::CoordinateCount { expected, got });
            }
        }
        if let Some(index) = q_ref.iter().position(|v| !v.is_finite()) {
            return Err(PlacementError::NonFiniteReference { index });
        }
        self.eval
            .evaluate(model, q, targets)
            .map_err(PlacementError::Eval)?;
        for (y, c) in self.y.iter_mut().zip(&self.eval.values()[self.m_eq..]) {
            *y = c.max(0.0).sqrt().max(Y_FLOOR);
        }
        self.lambda.fill(0.0);
        self.hy.fill(H_MIN);
        self.history.clear();
        self.update_residual();
        Ok(())
    }

    /// A step the merit (Newton) or the gain ratio (least squares) accepts,
    /// as its length α, raising the damping until one is; `None` when the
    /// damping passes `MU_MAX` (`it.status` then says why).
    fn accepted_step(
        &mut self,
        model: &Model,
        q: &[f64],
        q_ref: &[f64],
        targets: &[FingerTarget],
        opt: &Knobs,
        it: &mut Iterate,
    ) -> Option<f64> {
        loop {
            // Least-squares mode: matrix damping μ₀ + ν, pull μ₀/(μ₀ + ν).
            let (damp, pull) = match it.least_squares {
                false => (it.mu, 1.0),
                true => (opt.damping + it.nu, opt.damping / (opt.damping + it.nu)),
            };
            if self.newton_step(q, q_ref, damp, pull).is_err() {
                it.mu *= 100.0;
                it.nu = it.nu * 100.0 + opt.damping;
                it.regularised = true;
            } else {
                it.step = norm_inf(&self.dq).max(self.slack_step());
                if it.least_squares {
                    let psi = (it.theta, it.f, opt.damping);
                    if let Some(rho) = self.lm_trial(model, q, q_ref, targets, psi) {
                        it.nu = lm_update(it.nu, rho);
                        return Some(1.0);
                    }
                    it.nu = 4.0 * it.nu + opt.damping;
                } else {
                    let merit = Merit {
                        theta: it.theta,
                        f: it.f,
                        theta_ok: it.theta_ok,
                    };
                    if let Some(alpha) = self.line_search(model, q, q_ref, targets, merit) {
                        return Some(alpha);
                    }
                    it.mu *= 10.0;
                }
                it.regularised = true;
            }
            if it.mu.max(it.nu) > MU_MAX {
                it.status = self.stall_status(it.theta, opt.tolerance, it.step, opt.step_tolerance);
                return None;
            }
        }
    }

    /// After an accepted step of length `alpha` (θ was `theta_prev`):
    /// resets the damping, switches to least squares when the rows
    /// conflict; returns true when the solve ends (`it.status` says how).
    fn judge(&mut self, opt: &Knobs, it: &mut Iterate, alpha: f64, theta_prev: f64) -> bool {
        let theta = it.theta;
        // Levenberg–Marquardt: a full step resets μ to its floor, which
        // follows θ² (Yamashita–Fukushima): the damping bias μ|λ| then
        // vanishes faster than the residual, so convergence stays
        // quadratic even for rank-deficient but consistent rows.
        if alpha == 1.0 && !it.least_squares {
            it.mu = damping_floor(theta, opt.damping);
        }
        if theta <= opt.tolerance && it.step <= opt.step_tolerance && self.signs_ok() {
            it.status = SolveStatus::Converged;
            return true;
        }
        if it.least_squares && alpha * it.step <= opt.step_tolerance {
            it.status = SolveStatus::LeastSquares;
            return true;
        }
        // Newton contracts θ fast; a θ that stalls well above tolerance,
        // or a residual J can no longer reduce, means the rows conflict:
        // switch to the damped least-squares problem.
        it.stagnant = if theta > it.theta_ok && theta > STAGNATION * theta_prev {
            it.stagnant + 1
        } else {
            0
        };
        if !it.least_squares
            && (it.stagnant >= STAGNANT_STEPS
                || (theta > LS_ENTRY * opt.tolerance && self.gradient_ratio() <= LS_ENTRY_GRADIENT))
        {
            it.least_squares = true;
            it.nu = 0.0;
        }
        if theta > opt.tolerance && alpha * it.step <= opt.step_tolerance {
            it.status = self.stall_status(theta, opt.tolerance, it.step, opt.step_tolerance);
            return true;
        }
        false
    }

    /// The slack step in the rows' own units: the largest change of Y_j²
    /// (what C_j is compared with), |(Y_j + δY_j)² − Y_j²|. δY itself is in
    /// √metres: a row resting at its bound with no load (Y at `Y_FLOOR`,
    /// λ = 0) has Newton halve Y each iteration, so a step test on δY would
    /// take ten iterations to see what Y² (1e-12 m) shows at once (a joint
    /// limit placed exactly at the initial pose, Choi & Cremer Fig. 1's
    /// figure, `scenes/sit-on-chair.toml`).
    fn slack_step(&self) -> f64 {
        self.y
            .iter()
            .zip(&self.dy)
            .fold(0.0, |m, (y, d)| m.max(((y + d) * (y + d) - y * y).abs()))
    }

    /// ½‖q − q_ref‖²_W.
    pub(super) fn objective(&self, q: &[f64], q_ref: &[f64]) -> f64 {
        0.5 * q
            .iter()
            .zip(q_ref)
            .zip(&self.w)
            .map(|((a, b), w)| w * (a - b) * (a - b))
            .sum::<f64>()
    }

    /// Moves to the accepted trial: q, Y, λ, a full evaluation, H_Y, releases.
    fn commit(&mut self, model: &Model, q: &mut [f64], targets: &[FingerTarget]) {
        q.copy_from_slice(&self.q_trial);
        self.y.copy_from_slice(&self.y_trial);
        self.lambda.copy_from_slice(&self.lambda_new);
        // The trial evaluated without error, so the full one does too; on the
        // impossible error the values of the trial stay (C is already current).
        let _ = self.eval.evaluate(model, q, targets);
        let lam_in = &self.lambda[self.m_eq..];
        for ((h, y), l) in self.hy.iter_mut().zip(self.y.iter_mut()).zip(lam_in) {
            *h = (-2.0 * l).max(H_MIN);
            if *y < Y_FLOOR && *l > LAMBDA_PULL {
                *y = Y_FLOOR;
            }
        }
        self.update_residual();
    }

    /// No active inequality pulls (λ_j > 0 with Y_j ≈ 0).
    fn signs_ok(&self) -> bool {
        let lam_in = &self.lambda[self.m_eq..];
        self.y
            .iter()
            .zip(lam_in)
            .all(|(y, l)| *y >= Y_FLOOR || *l <= LAMBDA_PULL)
    }

    /// The status when no further progress is made at this point.
    fn stall_status(&mut self, theta: f64, tol: f64, step: f64, step_tol: f64) -> SolveStatus {
        if theta <= tol {
            return if step <= step_tol && self.signs_ok() {
                SolveStatus::Converged
            } else {
                SolveStatus::Stalled
            };
        }
        if self.gradient_ratio() <= LS_GRADIENT {
            SolveStatus::LeastSquares
        } else {
            SolveStatus::Stalled
        }
    }

    /// The report, from C at the returned q.
    fn info(
        &self,
        model: &Model,
        status: SolveStatus,
        iterations: u32,
        step: f64,
        regularised: bool,
        damping: f64,
    ) -> SolveInfo {
        let (mut all, mut len, mut ang) = (0.0, 0.0, 0.0);
        for (k, (c, row)) in self.eval.values().iter().zip(model.rows()).enumerate() {
            let v = if k < self.m_eq { *c } else { c.min(0.0) };
            all += v * v;
            match row.unit {
                RowUnit::Length => len += v * v,
                RowUnit::Angle => ang += v * v,
                RowUnit::Dimensionless => {}
            }
        }
        SolveInfo {
            status,
            iterations,
            residual: f64::sqrt(all),
            residual_length_m: f64::sqrt(len),
            residual_angle_rad: f64::sqrt(ang),
            step,
            regularised,
            damping,
        }
    }
}
