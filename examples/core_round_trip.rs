//! How long a cache line takes to go from one core to another and back:
//! two threads, each pinned to its own core, pass one atomic back and forth.
//! On the shared 2-core development machines this is 50-80 ns at some times
//! and 300-380 ns at others (the host moves the virtual CPUs), and lavapipe
//! as one device with a thread per core ran its `shade` kernel 1.6x slower
//! in the second case: the reason vkpt runs lavapipe as one device per core
//! (`vkpt::gpu::split`; docs/design-record.md, "lavapipe as one device per
//! core"). Run it beside a benchmark to
//! know which case the machine was in:
//!
//!     cargo run --release --example core_round_trip [FIRST_CORE SECOND_CORE]

use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Instant;

const ROUND_TRIPS: u64 = 200_000;

/// Pins the calling thread to `core`; false where the system refuses (no
/// such core, or not one this process may use).
fn pin_to(core: usize) -> bool {
    // SAFETY: a zeroed cpu_set_t is an empty set; CPU_SET and
    // sched_setaffinity read and write only the set passed to them.
    unsafe {
        let mut set: libc::cpu_set_t = std::mem::zeroed();
        libc::CPU_SET(core, &mut set);
        libc::sched_setaffinity(0, std::mem::size_of::<libc::cpu_set_t>(), &set) == 0
    }
}

fn main() {
    let cores: Vec<usize> = std::env::args()
        .skip(1)
        .map(|a| a.parse())
        .collect::<Result<_, _>>()
        .unwrap_or_else(|e| {
            eprintln!("core_round_trip: the cores must be numbers ({e})");
            std::process::exit(2)
        });
    let (first, second) = match cores[..] {
        [] => (0, 1),
        [a, b] => (a, b),
        _ => {
            eprintln!("usage: core_round_trip [FIRST_CORE SECOND_CORE]");
            std::process::exit(2)
        }
    };
    // Spinning threads that share a core would take a time slice per turn.
    if !(pin_to(second) && pin_to(first)) {
        eprintln!("core_round_trip: cannot pin threads to cores {first} and {second}");
        std::process::exit(2)
    }
    // Odd values: the second core's turn to answer; even: the first's.
    let turn = AtomicU64::new(0);
    std::thread::scope(|scope| {
        scope.spawn(|| {
            pin_to(second);
            for i in 0..ROUND_TRIPS {
                while turn.load(Ordering::Acquire) != 2 * i + 1 {
                    std::hint::spin_loop();
                }
                turn.store(2 * i + 2, Ordering::Release);
            }
        });
        let start = Instant::now();
        for i in 0..ROUND_TRIPS {
            turn.store(2 * i + 1, Ordering::Release);
            while turn.load(Ordering::Acquire) != 2 * i + 2 {
                std::hint::spin_loop();
            }
        }
        let ns = start.elapsed().as_secs_f64() * 1e9 / ROUND_TRIPS as f64;
        println!("cores {first} and {second}: round trip {ns:.0} ns");
    });
}
