//! Instructions per detection of every head on the Cortex-M4F, through the Rust API, run
//! under QEMU (`-machine mps2-an386 -icount shift=0`) by `tools/m4f_counts.sh`.
//!
//! With `-icount shift=0` QEMU advances its virtual clock by exactly 1 ns per executed
//! instruction, and SysTick, clocked by the board's 25 MHz CPU clock, counts one tick per
//! 40 ns: 40 instructions per tick, read before and after a batch. A batch is the first
//! [`ROWS`] rows of `examples/data/test.csv`, scored once each by one head in the loop of
//! an `#[inline(never)]` function (the head's call inlined into it or not, as the
//! compiler decides for any firmware); the same loop around a copy of the logits
//! (`noop`) is the cost of the loop alone. The heads run on `Table` (the shape fixed at
//! compile time), on the C API's `BoundedTable` (the shape read at run time) and on the
//! int8 `QTable`. Three calibration loops of known length (2 or 3 instructions per
//! iteration) check the counter before anything else is measured.
//!
//! For each batch the firmware also measures the deepest stack below the caller's
//! frame, by painting [`STACK_PROBE`] bytes under the stack pointer and finding the
//! lowest word that changed.
//!
//! Output lines, over semihosting: `calib NAME EXPECTED MEASURED` (instructions) and
//! `bench rust HEAD TABLE TICKS ROWS STACK CHECKSUM` (the checksum: the bits of the sum
//! of every row's first score, equal to the C API's for the same head and table).
#![no_std]
#![no_main]

#[path = "../rt.rs"]
mod rt;

use core::hint::black_box;

use cortex_m::peripheral::syst::SystClkSource;
use cortex_m_rt::entry;
use cortex_m_semihosting::{debug, hprintln};
use mlmap::baseline::sigmoid;
use mlmap::{Bounded, BoundedTable, FastMath, InferError, Libm, QTable, Scores, Table, TableView};

/// Detections per batch: the rows the host's instruction counts use too.
const ROWS: usize = 4096;

/// Bytes painted below the stack pointer before a batch.
const STACK_PROBE: usize = 8192;

/// The word the painted stack holds.
const PAINT: u32 = 0xA5A5_A5A5;

/// The shipped table and the test rows.
const TABLE_FILE: &[u8] = include_bytes!("../../../tables/default.mlmap");
const TEST_CSV: &str = include_str!("../../../examples/data/test.csv");

/// The small table with an open head (T = 1.75, epsilon = 0.05), and the same with a
/// recalibration map on every head (DESIGN §1.9).
const SMALL_OPEN_FILE: &[u8] = include_bytes!("../../../tests/golden/layer/small_open.mlmap");
const SMALL_MAPS_FILE: &[u8] = include_bytes!("../../../tests/golden/layer/small_maps.mlmap");

/// The shipped table quantized to int8 (scale 0.08, zero point 0 for every class).
const Q8_FILE: &[u8] = include_bytes!("../../../tables/default_q8.mlmap");

/// Scale of the int8 codes of `tables/default_q8.mlmap`.
const SCALE: f32 = 0.08;

type Shipped = Table<3, 22, 17, 22, 4>;
type Small = Table<3, 4, 2, 4, 4>;
type SmallMaps = Table<3, 4, 2, 4, 4, { mlmap::MAX_KNOTS }>;
type Q8<'a> = QTable<'a, 3, i8>;
/// The table type behind the C API's `mlmap_table_t` at its default maxima (16 classes,
/// 64 bins per head, 17 Bayes categories): the shape is read at run time.
type CTable = BoundedTable<16, 64, 64, 64, 17, { mlmap::MAX_KNOTS }, 1>;
/// Its view (built once, before the batches, as `ffi/examples/bounded_count.rs` does).
type CView<'a> = TableView<'a, Bounded<64>, Bounded<64>>;

/// One detection: logits and objectness.
#[derive(Clone, Copy)]
struct Row {
    x: [f32; 3],
    os: f32,
}

/// One detection as int8 codes.
#[derive(Clone, Copy)]
struct QRow {
    c: [i8; 3],
    os: f32,
}

/// The first `ROWS` rows of the test file (`id,label,objectness,car,cyclist,pedestrian`).
fn read_rows(rows: &mut [Row; ROWS]) -> bool {
    let mut lines = TEST_CSV.lines().skip(1);
    for row in rows.iter_mut() {
        let Some(line) = lines.next() else {
            return false;
        };
        let mut f = line.split(',').skip(2).map(str::parse::<f32>);
        let (Some(Ok(os)), Some(Ok(a)), Some(Ok(b)), Some(Ok(c))) =
            (f.next(), f.next(), f.next(), f.next())
        else {
            return false;
        };
        *row = Row { x: [a, b, c], os };
    }
    true
}

/// SysTick's current value (it counts down, 24 bits).
#[inline(always)]
fn now() -> u32 {
    cortex_m::peripheral::SYST::get_current()
}

/// Ticks from `a` to `b` of the down-counter.
#[inline(always)]
fn elapsed(a: u32, b: u32) -> u32 {
    a.wrapping_sub(b) & 0x00FF_FFFF
}

/// Paints the stack below the caller's frame; returns the stack pointer.
#[inline(always)]
fn paint() -> usize {
    let sp = cortex_m::register::msp::read() as usize;
    let bottom = sp - STACK_PROBE;
    let mut p = bottom;
    while p < sp - 64 {
        // SAFETY: unused RAM below the stack pointer (no interrupt is enabled).
        unsafe { core::ptr::write_volatile(p as *mut u32, PAINT) };
        p += 4;
    }
    sp
}

/// Bytes of stack used below `sp` since [`paint`].
#[inline(always)]
fn used_since(sp: usize) -> usize {
    let mut p = sp - STACK_PROBE;
    // SAFETY: the painted RAM.
    while p < sp - 64 && unsafe { core::ptr::read_volatile(p as *const u32) } == PAINT {
        p += 4;
    }
    sp - p
}

/// The instructions of `iterations` turns of a loop of `per_iteration` (2 or 3)
/// instructions, and what the counter measured.
fn calibrate(per_iteration: u32, iterations: u32) -> (u32, u32) {
    let empty = {
        let a = now();
        let b = now();
        elapsed(a, b)
    };
    let a = now();
    // SAFETY: a register loop without memory access.
    unsafe {
        if per_iteration == 2 {
            core::arch::asm!("2:", "subs {n}, #1", "bne 2b", n = inout(reg) iterations => _,
                options(nomem, nostack));
        } else {
            core::arch::asm!("2:", "nop", "subs {n}, #1", "bne 2b", n = inout(reg) iterations => _,
                options(nomem, nostack));
        }
    }
    let b = now();
    (per_iteration * iterations, (elapsed(a, b) - empty) * 40)
}

/// A batch through one head: the function `$name` scores every row (`$row`) with
/// `$call` on a table of type `$t`, and sums the first scores.
macro_rules! batch {
    ($name:ident, $t:ty, $row:ty, |$tt:ident, $r:ident| $call:expr) => {
        #[inline(never)]
        fn $name($tt: &$t, rows: &[$row]) -> f32 {
            let mut sum = 0.0f32;
            for $r in rows {
                let s: Result<Scores<3>, InferError> = $call;
                if let Ok(s) = s {
                    sum += s.0[0];
                }
            }
            sum
        }
    };
}

batch!(rust_noop, Shipped, Row, |_t, r| Ok(Scores(r.x)));
batch!(rust_sigmoid, Shipped, Row, |_t, r| sigmoid::<Libm, 3>(
    &r.x, r.os
));
batch!(rust_ml, Shipped, Row, |t, r| t.ml(&r.x, r.os));
batch!(rust_map, Shipped, Row, |t, r| t.map(&r.x, r.os));
batch!(rust_bayes, Shipped, Row, |t, r| t.bayes(&r.x, r.os));
batch!(rust_open, Shipped, Row, |t, r| t.open(&r.x, r.os));
batch!(rust_small_open, Small, Row, |t, r| t.open(&r.x, r.os));
batch!(rust_small_open_map, SmallMaps, Row, |t, r| t
    .open(&r.x, r.os));
/// A head on the C API's table type, from Rust, into arrays of the table's K.
macro_rules! scored {
    ($call:expr) => {{
        let mut out = [0.0f32; 3];
        $call(&mut out).map(|()| Scores(out))
    }};
}
batch!(bounded_ml, CView<'_>, Row, |v, r| scored!(
    |o: &mut [f32; 3]| v.ml_into(&r.x, r.os, o, &mut [0.0; 3])
));
batch!(bounded_map, CView<'_>, Row, |v, r| scored!(
    |o: &mut [f32; 3]| v.map_into::<Libm>(&r.x, r.os, o, &mut [0.0; 3])
));
batch!(bounded_bayes, CView<'_>, Row, |v, r| scored!(
    |o: &mut [f32; 3]| v.bayes_into::<FastMath>(&r.x, r.os, o, &mut [0.0; 4])
));
batch!(bounded_open, CView<'_>, Row, |v, r| scored!(
    |o: &mut [f32; 3]| v.open_into::<FastMath>(&r.x, r.os, o, &mut [0.0; 4])
));
batch!(rust_q8_noop, Q8<'_>, QRow, |_q, r| Ok(Scores(
    r.c.map(f32::from)
)));
batch!(rust_q8_ml, Q8<'_>, QRow, |q, r| q.ml(&r.c, r.os));
batch!(rust_q8_map, Q8<'_>, QRow, |q, r| q.map(&r.c, r.os));
batch!(rust_q8_bayes, Q8<'_>, QRow, |q, r| q.bayes(&r.c, r.os));
batch!(rust_q8_open, Q8<'_>, QRow, |q, r| q.open(&r.c, r.os));

/// Runs one batch: ticks, deepest stack and checksum, printed as one line.
fn run<T: ?Sized, R>(head: &str, table: &str, f: fn(&T, &[R]) -> f32, t: &T, rows: &[R]) {
    let f = black_box(f);
    let sp = paint();
    let a = now();
    let sum = f(t, rows);
    let b = now();
    let stack = used_since(sp);
    let empty = {
        let a = now();
        let b = now();
        elapsed(a, b)
    };
    hprintln!(
        "bench rust {} {} {} {} {} {:08x}",
        head,
        table,
        elapsed(a, b) - empty,
        rows.len(),
        stack,
        sum.to_bits()
    );
}

/// The int8 code of a logit: `clamp(round(x / SCALE), -128, 127)`, halves away from
/// zero (`f32::round`, which `core` lacks).
fn code(x: f32) -> i8 {
    let y = (x / SCALE).clamp(-128.0, 127.0);
    let t = y as i32; // toward zero; |y| <= 128, so `y - t` is exact
    let frac = y - t as f32;
    let r = if frac >= 0.5 {
        t + 1
    } else if frac <= -0.5 {
        t - 1
    } else {
        t
    };
    r.clamp(-128, 127) as i8
}

#[entry]
fn main() -> ! {
    let mut syst = cortex_m::Peripherals::take().map(|p| p.SYST);
    let Some(syst) = syst.as_mut() else {
        fail("no SysTick")
    };
    syst.set_clock_source(SystClkSource::Core);
    syst.set_reload(0x00FF_FFFF);
    syst.clear_current();
    syst.enable_counter();

    for (per, n) in [(2, 1_000_000), (3, 1_000_000), (2, 250_000)] {
        let (want, got) = calibrate(per, n);
        hprintln!("calib loop{} {} {}", per, want, got);
    }

    let mut rows = [Row {
        x: [0.0; 3],
        os: 0.0,
    }; ROWS];
    if !read_rows(&mut rows) {
        fail("test.csv: fewer rows than ROWS or a bad row");
    }
    let mut qrows = [QRow { c: [0; 3], os: 0.0 }; ROWS];
    for (q, r) in qrows.iter_mut().zip(rows.iter()) {
        *q = QRow {
            c: r.x.map(code),
            os: r.os,
        };
    }

    let Ok(shipped) = Shipped::from_bytes(black_box(TABLE_FILE)) else {
        fail("the shipped table does not decode")
    };
    let Ok(small) = Small::from_bytes(black_box(SMALL_OPEN_FILE)) else {
        fail("small_open.mlmap does not decode")
    };
    let Ok(maps) = SmallMaps::from_bytes(black_box(SMALL_MAPS_FILE)) else {
        fail("small_maps.mlmap does not decode")
    };
    let Some(Ok(q8)) =
        mlmap::section_of(black_box(Q8_FILE), mlmap::QUANTIZED_MAGIC).map(Q8::from_bytes)
    else {
        fail("default_q8.mlmap's section does not read")
    };

    let mut bounded = CTable::new();
    if bounded.decode(black_box(TABLE_FILE)).is_err() {
        fail("the shipped table does not decode into a BoundedTable")
    }
    let Some(view) = bounded.view() else {
        fail("an empty BoundedTable")
    };

    let r = &rows[..];
    run("noop", "default", rust_noop, &shipped, r);
    run("sigmoid", "default", rust_sigmoid, &shipped, r);
    run("ml", "default", rust_ml, &shipped, r);
    run("map", "default", rust_map, &shipped, r);
    run("bayes", "default", rust_bayes, &shipped, r);
    run("open", "default", rust_open, &shipped, r);
    run("ml", "bounded", bounded_ml, &view, r);
    run("map", "bounded", bounded_map, &view, r);
    run("bayes", "bounded", bounded_bayes, &view, r);
    run("open", "bounded", bounded_open, &view, r);
    run("open", "small_open", rust_small_open, &small, r);
    run("open", "small_maps", rust_small_open_map, &maps, r);
    let q = &qrows[..];
    run("q8_noop", "default_q8", rust_q8_noop, &q8, q);
    run("q8_ml", "default_q8", rust_q8_ml, &q8, q);
    run("q8_map", "default_q8", rust_q8_map, &q8, q);
    run("q8_bayes", "default_q8", rust_q8_bayes, &q8, q);
    run("q8_open", "default_q8", rust_q8_open, &q8, q);
    hprintln!("done");
    debug::exit(debug::EXIT_SUCCESS);
    loop {
        cortex_m::asm::wfi();
    }
}

/// Reports a failure and stops.
fn fail(what: &str) -> ! {
    hprintln!("FAILED: {}", what);
    rt::exit_failure()
}
