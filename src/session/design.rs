//! What a designer sees of design variables and objectives: the fast loop
//! tracks each design-variable component, each objective's reported value
//! and each named joint's motor torque (Nelson & Cohen §5.2, the joints with
//! `report_torque`) (start, end, min, max over the ticks that succeeded) and
//! streams them, one group per tick, through a lock-free queue to the
//! reporter, which adds them to `trace.csv` and (but the torques)
//! `design.svg`.
//!
//! The queue carries plain numbers: per tick the session time, then the
//! design components, the objectives' values and the joint torques
//! (`width` + 1 numbers). The
//! fast loop pushes a whole group or none (it checks the free room first; it
//! is the only producer), before that tick's trace samples, so a reporter
//! that has a tick's trace sample finds the tick's group complete.
//!
//! # Real-time
//! [`DesignTracker::record`] allocates nothing and takes no lock: O(design
//! components + objectives) arithmetic and queue pushes.

use crossbeam::queue::ArrayQueue;
use haptloop_solver::{Model, Program};
use std::collections::VecDeque;
use std::sync::Arc;

/// Ticks of design groups the queue holds: 16 s at 1 kHz.
const DESIGN_QUEUE_TICKS: usize = 1 << 14;

/// Start, end, smallest and largest value of one quantity over a run.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Range4 {
    /// At the start (after assembly).
    pub start: f64,
    /// After the last tick that succeeded.
    pub end: f64,
    /// Smallest over the ticks that succeeded.
    pub min: f64,
    /// Largest over the ticks that succeeded.
    pub max: f64,
}

impl Range4 {
    fn at(v: f64) -> Self {
        Self {
            start: v,
            end: v,
            min: v,
            max: v,
        }
    }

    /// Records a torque: the first finite one also becomes the start (no
    /// torque is known before a tick has solved).
    #[inline]
    fn record_torque(&mut self, v: f64) {
        if self.start.is_nan() && v.is_finite() {
            *self = Self::at(v);
        } else {
            self.record(v);
        }
    }

    #[inline]
    fn record(&mut self, v: f64) {
        self.end = v;
        // NaN never replaces a measurement (a failed report stays visible
        // as `end`).
        if v < self.min {
            self.min = v;
        }
        if v > self.max {
            self.max = v;
        }
    }
}

/// What the run did to each design component and objective.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct DesignStats {
    /// Design components (`"<joint>.length"`, `"<body>.position.x"`) and
    /// their ranges, in q order.
    pub variables: Vec<(String, Range4)>,
    /// Objectives: name, kind, weight and the range of the reported value.
    pub objectives: Vec<(String, String, f64, Range4)>,
    /// Named joints' motor torques: `"<joint>"` (N·m; N on a prismatic
    /// joint) and their ranges.
    pub torques: Vec<(String, Range4)>,
    /// Groups the reporter's queue had no room for.
    pub dropped: u64,
}

/// The fast loop's side: statistics and the producer end of the queue.
pub struct DesignTracker {
    cols: std::ops::Range<usize>,
    /// The statistics so far.
    pub stats: DesignStats,
    queue: Option<Arc<ArrayQueue<f64>>>,
}

impl DesignTracker {
    /// For `model` starting at `q` with the objectives' values `reports`
    /// (one per term); `None` when the model has neither design variables
    /// nor objectives. Also returns the reporter's end of the queue.
    /// Allocates.
    pub fn new(
        model: &Model,
        objectives: &Arc<haptloop_solver::Objectives>,
        q: &[f64],
    ) -> Option<(Self, DesignColumns)> {
        let layout = model.layout();
        let terms = &objectives.terms;
        let motors = model.torque_joints();
        if layout.design_coords() == 0 && terms.is_empty() && motors.is_empty() {
            return None;
        }
        let cols = layout.body_coords()..model.n_coords();
        let mut variables = Vec::with_capacity(cols.len());
        for d in layout.design_vars() {
            for k in 0..d.width {
                variables.push((d.component_name(k), Range4::at(q[d.offset + k])));
            }
        }
        let mut reports = vec![f64::NAN; terms.len()];
        let _ = objectives.evaluation(model).reports(model, q, &mut reports);
        let objectives: Vec<_> = terms
            .iter()
            .zip(&reports)
            .map(|(t, &v)| (t.name.clone(), t.kind.to_string(), t.weight, Range4::at(v)))
            .collect();
        // Not measured until the first tick has solved.
        let torques: Vec<(String, Range4)> = motors
            .iter()
            .map(|c| {
                (
                    model.constraints()[c.index()].name.clone(),
                    Range4::at(f64::NAN),
                )
            })
            .collect();
        let width = variables.len() + objectives.len() + torques.len();
        let queue = Arc::new(ArrayQueue::new(DESIGN_QUEUE_TICKS * (width + 1)));
        let unit = |c: &haptloop_solver::ConstraintId| match model.constraints()[c.index()].kind {
            haptloop_solver::ConstraintKind::Prismatic => "n",
            _ => "nm",
        };
        let names = variables
            .iter()
            .map(|(n, _)| format!("{n}_m"))
            .chain(objectives.iter().map(|(n, ..)| format!("objective_{n}")))
            .chain(
                torques
                    .iter()
                    .zip(motors)
                    .map(|((n, _), c)| format!("torque_{n}_{}", unit(c))),
            )
            .collect();
        let mut columns = DesignColumns::new(queue.clone(), names, variables.len());
        columns.torques = torques.len();
        Some((
            Self {
                cols,
                stats: DesignStats {
                    variables,
                    objectives,
                    torques,
                    dropped: 0,
                },
                queue: Some(queue),
            },
            columns,
        ))
    }

    /// Records the tick at `t_s` after `program` ticked (`solved`: its
    /// solve succeeded), and queues its group for the reporter.
    ///
    /// # Real-time
    /// No allocation, no lock.
    #[inline]
    pub fn record(&mut self, t_s: f64, program: &Program, solved: bool) {
        let q = program.q();
        if q.len() < self.cols.end {
            return;
        }
        let values = &q[self.cols.clone()];
        let reports = program.objective_reports();
        let torques = program.joint_torques();
        if solved {
            for ((_, r), &v) in self.stats.variables.iter_mut().zip(values) {
                r.record(v);
            }
            for ((.., r), &v) in self.stats.objectives.iter_mut().zip(reports) {
                r.record(v);
            }
            for ((_, r), &v) in self.stats.torques.iter_mut().zip(torques) {
                r.record_torque(v);
            }
        }
        let Some(queue) = &self.queue else { return };
        let width =
            self.stats.variables.len() + self.stats.objectives.len() + self.stats.torques.len();
        if queue.capacity() - queue.len() < width + 1 {
            self.stats.dropped += 1;
            return;
        }
        let _ = queue.push(t_s);
        for &v in values {
            let _ = queue.push(v);
        }
        for k in 0..self.stats.objectives.len() {
            let _ = queue.push(reports.get(k).copied().unwrap_or(f64::NAN));
        }
        for k in 0..self.stats.torques.len() {
            let _ = queue.push(torques.get(k).copied().unwrap_or(f64::NAN));
        }
    }
}

/// The reporter's side: the column names and the groups drained so far.
pub struct DesignColumns {
    queue: Arc<ArrayQueue<f64>>,
    /// `trace.csv` column names: design components (`…_m`), then objectives.
    pub names: Vec<String>,
    /// How many of `names` are design components.
    pub variables: usize,
    /// How many of `names`, at the end, are joint torques.
    pub torques: usize,
    partial: Vec<f64>,
    pending: VecDeque<Vec<f64>>,
}

impl DesignColumns {
    fn new(queue: Arc<ArrayQueue<f64>>, names: Vec<String>, variables: usize) -> Self {
        Self {
            queue,
            partial: Vec::with_capacity(names.len() + 1),
            names,
            variables,
            torques: 0,
            pending: VecDeque::new(),
        }
    }

    /// Pulls one whole group (time, values) from the queue, if there is one.
    fn pull(&mut self) -> Option<Vec<f64>> {
        while self.partial.len() < self.names.len() + 1 {
            self.partial.push(self.queue.pop()?);
        }
        Some(std::mem::replace(
            &mut self.partial,
            Vec::with_capacity(self.names.len() + 1),
        ))
    }

    /// The group of the tick at `t_s` (values only), if it was queued:
    /// older groups are dropped, the group is kept for the tick's other
    /// fingers.
    pub fn at(&mut self, t_s: f64) -> Option<&[f64]> {
        loop {
            match self.pending.front() {
                Some(g) if g[0] < t_s => {
                    self.pending.pop_front();
                }
                Some(_) => break,
                None => match self.pull() {
                    Some(g) => self.pending.push_back(g),
                    None => break,
                },
            }
        }
        self.pending
            .front()
            .filter(|g| g[0] == t_s)
            .map(|g| &g[1..])
    }
}

/// The design flags of a run (`[[design_flag]]`, `--design-on/off`): the
/// fast loop switches each variable on or off at its session time, before
/// the tick that starts at or after it (Nelson & Cohen §3's flags).
///
/// # Real-time
/// [`DesignSchedule::apply`] allocates nothing: a cursor over a list made
/// before the run.
#[derive(Debug, Clone, Default)]
pub struct DesignSchedule {
    /// (time, design variable index, on), by time.
    events: Vec<(f64, usize, bool)>,
    next: usize,
}

impl DesignSchedule {
    /// From the scene's switches (sorted by time). Allocates.
    pub fn new(flags: &[haptloop_solver::scene::DesignFlagDecl]) -> Self {
        Self {
            events: flags.iter().map(|f| (f.at_s, f.var, f.on)).collect(),
            next: 0,
        }
    }

    /// Applies every switch due at `t_s` to `program`.
    #[inline]
    pub fn apply(&mut self, t_s: f64, program: &mut Program) {
        while let Some(&(at, var, on)) = self.events.get(self.next) {
            if at > t_s {
                break;
            }
            let _ = program.set_design_active(var, on);
            self.next += 1;
        }
    }
}
