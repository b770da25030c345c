//! The program hand-over: a bounded queue that moves boxed programs from the
//! slow thread to the fast thread, and a return queue that carries each
//! replaced program back so it is dropped off the real-time thread.
//!
//! Both queues are crossbeam's `ArrayQueue` (bounded, lock-free, buffer
//! allocated at construction; `push`/`pop` never allocate), which needs no
//! `unsafe` of ours. Moving a `Box<P>` moves one pointer.
//!
//! **No drop on the fast thread, by construction.** The sender counts programs
//! *in flight* (sent, not yet collected back) and refuses to send more than the
//! capacity. Programs waiting in the return queue are a subset of those in
//! flight, so the return queue (same capacity) always has room for the one the
//! fast thread gives back: the fast thread never has to keep, drop or block on a
//! replaced program. The slow side must call [`ProgramSender::collect`] (which
//! drops returned programs on its own thread) to regain credit.
//!
//! # Real-time
//! [`ProgramReceiver::try_swap`] allocates nothing, takes no lock and does at
//! most `capacity` pops and pushes; it never deallocates a program.

use crossbeam::queue::ArrayQueue;
use std::sync::Arc;

struct Queues<P> {
    to_fast: ArrayQueue<Box<P>>,
    to_slow: ArrayQueue<Box<P>>,
}

/// The slow thread's end: sends new programs, collects replaced ones.
pub struct ProgramSender<P> {
    queues: Arc<Queues<P>>,
    capacity: usize,
    in_flight: usize,
}

/// The fast thread's end: swaps in new programs at a tick boundary.
pub struct ProgramReceiver<P> {
    queues: Arc<Queues<P>>,
    swapped: u64,
    leaked: u64,
}

/// Why a program could not be sent; carries the program back.
#[derive(Debug)]
pub enum SendError<P> {
    /// `capacity` programs are in flight: collect returned ones first.
    Full(Box<P>),
}

/// Creates a hand-over with room for `capacity` programs in flight (≥ 1).
pub fn program_channel<P: Send>(capacity: usize) -> (ProgramSender<P>, ProgramReceiver<P>) {
    let capacity = capacity.max(1);
    let queues = Arc::new(Queues {
        to_fast: ArrayQueue::new(capacity),
        to_slow: ArrayQueue::new(capacity),
    });
    (
        ProgramSender {
            queues: queues.clone(),
            capacity,
            in_flight: 0,
        },
        ProgramReceiver {
            queues,
            swapped: 0,
            leaked: 0,
        },
    )
}

impl<P: Send> ProgramSender<P> {
    /// Queues `program` for the fast thread. Fails (returning it) while
    /// `capacity` programs are in flight; never blocks.
    pub fn try_send(&mut self, program: Box<P>) -> Result<(), SendError<P>> {
        if self.in_flight >= self.capacity {
            return Err(SendError::Full(program));
        }
        match self.queues.to_fast.push(program) {
            Ok(()) => {
                self.in_flight += 1;
                Ok(())
            }
            // Unreachable while the credit invariant holds (to_fast.len() ≤
            // in_flight < capacity); report it as Full rather than panic.
            Err(program) => Err(SendError::Full(program)),
        }
    }

    /// Takes one replaced program back from the fast thread (the caller drops
    /// it, here, off the real-time thread) and regains one credit.
    pub fn collect(&mut self) -> Option<Box<P>> {
        let p = self.queues.to_slow.pop()?;
        self.in_flight -= 1;
        Some(p)
    }

    /// Drops every replaced program that has come back; returns how many.
    pub fn collect_all(&mut self) -> usize {
        let mut n = 0;
        while self.collect().is_some() {
            n += 1;
        }
        n
    }

    /// Programs sent and not yet matched by a collected return. The running
    /// program is not counted: the initial one, returned when the first sent
    /// program replaces it, balances it.
    pub fn in_flight(&self) -> usize {
        self.in_flight
    }
}

impl<P: Send> ProgramReceiver<P> {
    /// Swaps every waiting program into `current`, oldest first, so the newest
    /// ends up current. Before each swap `carry(old, new)` may move state that
    /// survives (configuration, multipliers) from the running program into the
    /// new one. Each replaced program goes back to the slow thread. Returns the
    /// number of programs swapped in (0 when none were waiting).
    ///
    /// # Real-time
    /// No allocation or deallocation; at most `capacity` iterations plus the
    /// cost of `carry`.
    pub fn try_swap(&mut self, current: &mut Box<P>, mut carry: impl FnMut(&P, &mut P)) -> usize {
        let mut n = 0;
        while let Some(mut incoming) = self.queues.to_fast.pop() {
            carry(current, &mut incoming);
            std::mem::swap(current, &mut incoming);
            if let Err(replaced) = self.queues.to_slow.push(incoming) {
                // Impossible while the credit invariant holds. Never drop (free)
                // on the fast thread: leak it and count the leak instead.
                std::mem::forget(replaced);
                self.leaked += 1;
            }
            n += 1;
        }
        self.swapped += n as u64;
        n
    }

    /// Programs swapped in so far.
    pub fn swapped(&self) -> u64 {
        self.swapped
    }

    /// Programs that could not be returned and were leaked rather than freed on
    /// the fast thread. Always 0 unless the credit invariant is broken.
    pub fn leaked(&self) -> u64 {
        self.leaked
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn credits_bound_in_flight_programs_and_carry_moves_state() {
        let (mut tx, mut rx) = program_channel::<Vec<u32>>(2);
        let mut current = Box::new(vec![0]);
        tx.try_send(Box::new(vec![1])).unwrap();
        tx.try_send(Box::new(vec![2])).unwrap();
        assert!(matches!(
            tx.try_send(Box::new(vec![3])),
            Err(SendError::Full(_))
        ));
        let n = rx.try_swap(&mut current, |old, new| new.push(old[0] + 100));
        assert_eq!(n, 2);
        // Newest wins; carry ran old→new each time: [1, 100] then [2, 101].
        assert_eq!(*current, vec![2, 101]);
        assert_eq!(tx.in_flight(), 2, "not collected yet");
        assert!(matches!(
            tx.try_send(Box::new(vec![4])),
            Err(SendError::Full(_))
        ));
        let returned: Vec<Vec<u32>> = std::iter::from_fn(|| tx.collect().map(|b| *b)).collect();
        assert_eq!(returned, vec![vec![0], vec![1, 100]]);
        assert_eq!(tx.in_flight(), 0);
        assert_eq!(rx.try_swap(&mut current, |_, _| {}), 0);
        assert_eq!((rx.swapped(), rx.leaked()), (2, 0));
    }
}
