//! `Controller::tick` allocates nothing: a counting global allocator around thousands of
//! ticks of the LQG servo (rotated gains and per-tick solve) and the PID baseline, through
//! measurements, dropouts, jittery Δ (which re-solves the body-frame gains), saturation and
//! refused inputs. The count is per thread (the test harness's own threads allocate
//! whenever they like).

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;

use dronecine_profile::Profile;
use dronecine_servo::control::{Controller, Measurement, Reference, TickInput};
use dronecine_servo::lqg::{LqgServo, ServoOptions};
use dronecine_servo::pid::PidController;

struct Counting;

thread_local! {
    /// Allocations and bytes asked for by this thread (const-initialised: reading it does
    /// not allocate).
    static ALLOCATIONS: Cell<usize> = const { Cell::new(0) };
    static BYTES: Cell<usize> = const { Cell::new(0) };
}

fn counted(size: usize) {
    // `try_with`: the thread-locals may be gone while a thread shuts down.
    let _ = ALLOCATIONS.try_with(|a| a.set(a.get() + 1));
    let _ = BYTES.try_with(|b| b.set(b.get() + size));
}

fn counts() -> (usize, usize) {
    (ALLOCATIONS.with(Cell::get), BYTES.with(Cell::get))
}

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        counted(layout.size());
        unsafe { System.alloc(layout) }
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) }
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        counted(new_size);
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

fn input(k: usize) -> TickInput {
    let dt = 0.01 + 0.004 * (k as f64 * 0.37).sin();
    let t = k as f64 * 0.01;
    let (s, c) = (0.5 * t).sin_cos();
    TickInput {
        t_s: t,
        dt_s: match k % 97 {
            0 => 0.0,      // refused: time stood still
            1 => f64::NAN, // refused: not finite
            _ => dt,
        },
        measurement: (!k.is_multiple_of(13)).then_some(Measurement {
            position_m: [c, s, 1.0 + 0.001 * (k % 7) as f64],
            heading_rad: 3.0 * s,
        }),
        reference: Reference {
            // Every 500 ticks the reference jumps far away: saturated commands.
            position_m: if (k / 500) % 2 == 1 {
                [5.0 * c, -4.0, 3.0]
            } else {
                [c, s, 1.0]
            },
            velocity_mps: [-0.5 * s, 0.5 * c, 0.0],
            acceleration_mps2: [-0.25 * c, -0.25 * s, 0.0],
            heading_rad: -3.0 * s,
            heading_rate_radps: -1.5 * c,
        },
    }
}

fn count(ctl: &mut dyn Controller) -> (usize, usize) {
    ctl.reset(
        0.0,
        &Measurement {
            position_m: [1.0, 0.0, 1.0],
            heading_rad: 0.0,
        },
    );
    let inputs: Vec<TickInput> = (1..5000).map(input).collect();
    let (a0, b0) = counts();
    let mut ok = 0usize;
    for i in &inputs {
        if let Ok(o) = ctl.tick(i) {
            ok += usize::from(o.command.is_finite());
        }
    }
    let (a1, b1) = counts();
    assert!(ok > 4800, "{ok}");
    (a1 - a0, b1 - b0)
}

#[test]
fn ticks_allocate_nothing() {
    let profile = Profile::builtin("ardrone2").unwrap();
    let mut lqg = LqgServo::new(&profile, ServoOptions::default()).unwrap();
    let mut per_tick = LqgServo::new(
        &profile,
        ServoOptions {
            per_tick_solve: true,
            ..ServoOptions::default()
        },
    )
    .unwrap();
    let mut paper = LqgServo::new(
        &profile,
        ServoOptions {
            paper_prefilter: true,
            ..ServoOptions::default()
        },
    )
    .unwrap();
    let mut pid = PidController::new(&profile);
    // The counter works: a Vec allocates.
    let before = counts().0;
    let v: Vec<u64> = std::hint::black_box(vec![1, 2, 3]);
    assert!(counts().0 > before && v.len() == 3);
    for (name, ctl) in [
        ("lqg", &mut lqg as &mut dyn Controller),
        ("lqg per-tick solve", &mut per_tick),
        ("lqg paper pre-filter", &mut paper),
        ("pid", &mut pid),
    ] {
        let (n, bytes) = count(ctl);
        assert_eq!((n, bytes), (0, 0), "{name}: {n} allocations, {bytes} bytes");
    }
}
