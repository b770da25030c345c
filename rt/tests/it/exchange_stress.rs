//! Two-thread stress tests with checksummed payloads: no torn read, no loss
//! beyond the documented overwrite semantics.

use haptloop_rt::exchange::{mailbox, program_channel};

/// splitmix64: a cheap, well-mixed function of the sequence number.
fn mix(mut x: u64) -> u64 {
    x = x.wrapping_add(0x9E37_79B9_7F4A_7C15);
    x = (x ^ (x >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    x = (x ^ (x >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    x ^ (x >> 31)
}

#[derive(Clone)]
struct Payload {
    seq: u64,
    data: [u64; 30],
    check: u64,
}

impl Payload {
    fn fill(&mut self, seq: u64) {
        self.seq = seq;
        let mut acc = seq;
        for (i, d) in self.data.iter_mut().enumerate() {
            *d = mix(seq * 31 + i as u64);
            acc = acc.rotate_left(5) ^ *d;
        }
        self.check = acc;
    }

    fn is_intact(&self) -> bool {
        let mut acc = self.seq;
        for (i, d) in self.data.iter().enumerate() {
            if *d != mix(self.seq * 31 + i as u64) {
                return false;
            }
            acc = acc.rotate_left(5) ^ *d;
        }
        acc == self.check
    }
}

#[test]
fn mailbox_reader_never_sees_a_torn_or_older_snapshot() {
    const N: u64 = 300_000;
    let empty = || Payload {
        seq: 0,
        data: [0; 30],
        check: 0,
    };
    let (mut w, mut r) = mailbox(|| {
        let mut p = empty();
        p.fill(0);
        p
    });
    let writer = std::thread::spawn(move || {
        for seq in 1..=N {
            w.publish_with(|p| p.fill(seq));
        }
    });
    let (mut last, mut reads, mut distinct) = (0u64, 0u64, 0u64);
    while last < N {
        let (seq, intact) = r.read(|p| (p.seq, p.is_intact()));
        assert!(intact, "torn snapshot at seq {seq}");
        assert!(seq >= last, "went back from {last} to {seq}");
        distinct += u64::from(seq > last);
        last = seq;
        reads += 1;
    }
    writer.join().unwrap();
    assert_eq!(last, N, "the final value is always delivered");
    assert!(reads > 0 && distinct > 0);
}

#[test]
fn every_program_is_swapped_in_once_and_returned_intact() {
    const N: u64 = 20_000;
    let make = |id: u64| {
        let mut p = Payload {
            seq: 0,
            data: [0; 30],
            check: 0,
        };
        p.fill(id);
        Box::new((p, 0u64)) // (payload, generation carried across swaps)
    };
    let (mut tx, mut rx) = program_channel(4);
    let fast = std::thread::spawn(move || {
        let mut current = make(0);
        let mut swapped = 0u64;
        while swapped < N {
            swapped += rx.try_swap(&mut current, |old, new| {
                assert!(new.0.is_intact(), "program {} arrived torn", new.0.seq);
                new.1 = old.1 + 1;
            }) as u64;
            std::hint::spin_loop();
        }
        (current, rx.leaked())
    });
    let (mut next, mut returned_ids) = (1u64, 0u64);
    let mut returned = 0u64;
    while returned < N {
        if next <= N {
            match tx.try_send(make(next)) {
                Ok(()) => next += 1,
                Err(_) => std::thread::yield_now(),
            }
        }
        while let Some(p) = tx.collect() {
            assert!(p.0.is_intact(), "program {} came back torn", p.0.seq);
            returned_ids += p.0.seq;
            returned += 1;
        }
    }
    let (current, leaked) = fast.join().unwrap();
    assert_eq!(leaked, 0);
    assert_eq!(current.0.seq, N, "the newest program is current");
    assert_eq!(current.1, N, "carry ran once per swap, in order");
    // Returned: the initial program 0 and programs 1 … N−1, each exactly once.
    assert_eq!(returned_ids, (N - 1) * N / 2);
    // Credits: N sent, N collected (the initial program's return stands in for
    // the one now current), so the sender may send `capacity` more.
    assert_eq!(tx.in_flight(), 0);
}
