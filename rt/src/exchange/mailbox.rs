//! The latest-value mailbox: a triple buffer.
//!
//! The fast loop publishes a snapshot every tick; the slow loop reads the newest
//! complete one whenever it likes. Three slots are partitioned between the
//! writer, the reader and a shared "back" slot; each side only ever touches its
//! own slot, and hands it over with a single atomic exchange of the back index
//! (plus a *fresh* bit saying the back slot holds a newer value than the
//! reader's). This is the classic triple buffer (as in the `triple_buffer`
//! crate), chosen over a seqlock because the reader never retries and never sees
//! a torn value by construction, and over a queue because the slow loop wants
//! only the newest state, not every one. The cost: three copies of `T`, and a
//! writer that always overwrites a slot whose old contents are two publishes
//! stale (so write every field, or use [`MailboxWriter::publish_with`] on a
//! value that is fully rewritten each time).
//!
//! Overwrite semantics: a value published while the reader has not yet picked
//! up the previous one replaces it. The reader sees a subsequence of the
//! published values, in order, always ending with the last one published before
//! its most recent read.
//!
//! # Real-time
//! [`MailboxWriter::publish_with`] does not allocate, lock, make a syscall or
//! wake the reader: it runs the caller's closure on the writer's own slot and
//! does one atomic swap. It is wait-free.

use super::sync::{Arc, AtomicU8, Ordering, UnsafeCell};
use crossbeam::utils::CachePadded;

const INDEX_MASK: u8 = 0b011;
const FRESH: u8 = 0b100;

struct Shared<T> {
    slots: [CachePadded<UnsafeCell<T>>; 3],
    /// Index of the back slot, with [`FRESH`] set when it holds a value the
    /// reader has not taken yet.
    back: CachePadded<AtomicU8>,
}

// SAFETY: at any moment each slot is owned by exactly one of {writer, back,
// reader}; the writer and reader only dereference the slot they own, and
// ownership moves only through the AcqRel swap on `back`, which orders every
// access to a slot before the next owner's accesses. So `T` values are only ever
// moved between threads (needs `Send`), never shared (no `Sync` needed).
unsafe impl<T: Send> Sync for Shared<T> {}
// SAFETY: as above; the slots hold `T: Send` values.
unsafe impl<T: Send> Send for Shared<T> {}

/// The writing end of a mailbox (one per mailbox; the fast loop's side).
pub struct MailboxWriter<T> {
    shared: Arc<Shared<T>>,
    index: u8,
}

/// The reading end of a mailbox (one per mailbox; the slow loop's side).
pub struct MailboxReader<T> {
    shared: Arc<Shared<T>>,
    index: u8,
}

/// Creates a mailbox whose three slots are each initialised by `init` (so a
/// snapshot with preallocated vectors is allocated here, once, and never again).
/// Until the first publish, the reader sees an `init()` value.
pub fn mailbox<T: Send>(mut init: impl FnMut() -> T) -> (MailboxWriter<T>, MailboxReader<T>) {
    let shared = Arc::new(Shared {
        slots: [
            CachePadded::new(UnsafeCell::new(init())),
            CachePadded::new(UnsafeCell::new(init())),
            CachePadded::new(UnsafeCell::new(init())),
        ],
        back: CachePadded::new(AtomicU8::new(1)),
    });
    (
        MailboxWriter {
            shared: shared.clone(),
            index: 0,
        },
        MailboxReader { shared, index: 2 },
    )
}

impl<T: Send> MailboxWriter<T> {
    /// Fills the writer's slot with `fill` and publishes it as the newest value.
    ///
    /// The slot passed to `fill` holds an older value (from two publishes ago, or
    /// `init()`): overwrite every field that matters.
    ///
    /// # Real-time
    /// Wait-free; allocates only if `fill` does.
    #[inline]
    pub fn publish_with(&mut self, fill: impl FnOnce(&mut T)) {
        self.shared.slots[usize::from(self.index)].with_mut(|slot| {
            // SAFETY: the writer owns slot `self.index` (see `Shared`): nobody
            // else reads or writes it until the swap below hands it over.
            fill(unsafe { &mut *slot })
        });
        let previous = self.shared.back.swap(self.index | FRESH, Ordering::AcqRel);
        self.index = previous & INDEX_MASK;
    }

    /// True if the reader has taken the last value published (or nothing
    /// was published yet): the next value is the first it has not seen.
    /// The reader may take a value just after this says false; a writer
    /// that accumulates over the values the reader missed then reports a
    /// little more than it needs to, never less.
    ///
    /// # Real-time
    /// One relaxed atomic load.
    #[inline]
    pub fn reader_is_current(&self) -> bool {
        self.shared.back.load(Ordering::Relaxed) & FRESH == 0
    }

    /// Publishes `value`, dropping the slot's old value on this thread: use
    /// [`Self::publish_with`] for types that own heap memory.
    #[inline]
    pub fn publish(&mut self, value: T) {
        self.publish_with(|slot| *slot = value);
    }
}

impl<T: Send> MailboxReader<T> {
    /// Takes the newest published value if there is one the reader has not seen.
    /// Returns true if the reader's value changed.
    pub fn refresh(&mut self) -> bool {
        if self.shared.back.load(Ordering::Relaxed) & FRESH == 0 {
            return false;
        }
        let previous = self.shared.back.swap(self.index, Ordering::AcqRel);
        self.index = previous & INDEX_MASK;
        true
    }

    /// Refreshes, then runs `f` on the newest complete value.
    pub fn read<R>(&mut self, f: impl FnOnce(&T) -> R) -> R {
        self.refresh();
        self.shared.slots[usize::from(self.index)].with(|slot| {
            // SAFETY: the reader owns slot `self.index` until its next swap, which
            // needs `&mut self` and so cannot happen while `f` runs.
            f(unsafe { &*slot })
        })
    }

    /// Refreshes and borrows the newest complete value.
    #[cfg(not(loom))]
    pub fn latest(&mut self) -> &T {
        self.refresh();
        let slot = self.shared.slots[usize::from(self.index)].with(|slot| slot);
        // SAFETY: the reader owns this slot until its next swap, which needs
        // `&mut self`; the returned borrow of `self` prevents that swap.
        unsafe { &*slot }
    }
}

#[cfg(all(test, not(loom)))]
mod tests {
    use super::*;

    #[test]
    fn reader_sees_init_then_latest_and_skips_overwritten() {
        let (mut w, mut r) = mailbox(|| 0u64);
        assert_eq!(*r.latest(), 0);
        assert!(!r.refresh());
        w.publish(1);
        w.publish(2);
        w.publish(3);
        assert_eq!(*r.latest(), 3);
        assert!(!r.refresh(), "no newer value than 3");
        w.publish(4);
        assert_eq!(r.read(|v| *v), 4);
    }

    #[test]
    fn the_writer_knows_whether_the_reader_took_its_last_value() {
        let (mut w, mut r) = mailbox(|| 0u64);
        assert!(w.reader_is_current(), "nothing published yet");
        w.publish(1);
        assert!(!w.reader_is_current());
        w.publish(2);
        assert!(!w.reader_is_current(), "1 was overwritten unseen, 2 unseen");
        assert_eq!(*r.latest(), 2);
        assert!(w.reader_is_current());
        assert!(!r.refresh());
        assert!(
            w.reader_is_current(),
            "a refresh with nothing new changes nothing"
        );
        w.publish(3);
        assert!(!w.reader_is_current());
    }

    #[test]
    fn publish_with_reuses_preallocated_slots() {
        let (mut w, mut r) = mailbox(|| Vec::<f64>::with_capacity(8));
        for k in 0..10 {
            w.publish_with(|s| {
                s.clear();
                s.extend((0..8).map(|i| (k * 8 + i) as f64));
            });
        }
        assert_eq!(r.latest()[0], 72.0);
        assert_eq!(r.latest().len(), 8);
    }
}
