//! Lock-free exchange between the fast loop and the slow loop.
//!
//! | direction | what | type | built on |
//! |---|---|---|---|
//! | fast → slow | newest state snapshot, every tick | [`mailbox`] → [`MailboxWriter`] / [`MailboxReader`] | a triple buffer (this crate's only `unsafe`, model-checked with loom) |
//! | slow → fast | a new boxed program | [`program_channel`] → [`ProgramSender`] / [`ProgramReceiver`] | crossbeam `ArrayQueue`, credit-bounded |
//! | fast → slow | the replaced program, to be dropped off the fast thread | (same channel) | crossbeam `ArrayQueue` |
//!
//! Neither side ever blocks on the other, and the fast side never allocates,
//! frees or wakes a thread. The slow side polls at its own rate: waking it from
//! the fast thread would cost a futex syscall and a cross-CPU IPI (≈ 10 µs
//! median measured on the development VM with a futex ping-pong between two
//! pinned threads).

mod handover;
mod mailbox;
mod sync;

pub use handover::{ProgramReceiver, ProgramSender, SendError, program_channel};
pub use mailbox::{MailboxReader, MailboxWriter, mailbox};

/// Loom model checks of the mailbox. Run with
/// `RUSTFLAGS="--cfg loom" cargo test -p haptloop-rt --release --lib exchange::loom_tests`.
#[cfg(all(test, loom))]
mod loom_tests {
    use super::mailbox;

    /// A payload whose halves must always agree: a torn read would break it.
    #[derive(Clone, Copy)]
    struct Pair(u64, u64);

    #[test]
    fn reader_never_sees_a_torn_or_older_value() {
        loom::model(|| {
            let (mut w, mut r) = mailbox(|| Pair(0, 0));
            let writer = loom::thread::spawn(move || {
                for k in 1..=3u64 {
                    w.publish_with(|s| {
                        s.0 = k;
                        s.1 = k * 10;
                    });
                }
            });
            let mut last = 0;
            for _ in 0..2 {
                let (a, b) = r.read(|p| (p.0, p.1));
                assert_eq!(b, a * 10, "torn read");
                assert!(a >= last, "went back in time: {a} after {last}");
                last = a;
            }
            writer.join().unwrap();
            // After the writer is done, the newest value is visible.
            let (a, b) = r.read(|p| (p.0, p.1));
            assert_eq!((a, b), (3, 30));
        });
    }
}
