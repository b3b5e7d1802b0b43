//! Per-call time of a closure for the ratios the benches print.
//!
//! The fastest of many short batches of wall-clock time: on a shared machine a batch
//! can only be slowed down (preempted, interrupted), never sped up, so the minimum is
//! the undisturbed time. (A thread's CPU time from `/proc` is only updated at scheduler
//! ticks, a few milliseconds apart, far too coarse for calls of a microsecond.)

use std::hint::black_box;
use std::time::{Duration, Instant};

/// Fastest time per call of `f`, in ns, over 201 batches of about 0.2 ms each.
pub(crate) fn min_ns<R>(mut f: impl FnMut() -> R) -> f64 {
    // Calls per batch: enough for about 0.2 ms.
    let mut calls = 1u32;
    loop {
        let start = Instant::now();
        for _ in 0..calls {
            black_box(f());
        }
        if start.elapsed() >= Duration::from_micros(200) || calls >= 1 << 20 {
            break;
        }
        calls *= 2;
    }
    (0..201)
        .map(|_| {
            let start = Instant::now();
            for _ in 0..calls {
                black_box(f());
            }
            start.elapsed().as_secs_f64() * 1e9 / f64::from(calls)
        })
        .fold(f64::INFINITY, f64::min)
}

/// The instruction-counting request of a bench: the name in `name_var` and the call
/// count in `calls_var` (default 1), `None` when `name_var` is not set. Running one
/// thing `n` times under `valgrind --tool=callgrind` with two values of `n`, the
/// difference of the instruction counts over the difference of `n` is its
/// instructions per call, repeatable on a loaded machine.
#[allow(dead_code)] // Only the benches that count instructions ask for it.
pub(crate) fn only_request(name_var: &str, calls_var: &str) -> Option<(String, usize)> {
    let name = std::env::var(name_var).ok()?;
    let calls = std::env::var(calls_var)
        .ok()
        .and_then(|n| n.parse().ok())
        .unwrap_or(1);
    Some((name, calls))
}
