//! The choreography core in wasm (issue 5's benchmark): the built-in library, the ≥ 2,000
//! segment library of `odori_tests::builtin_medley_library` (no file access in wasm), the
//! transition table in one go and in slices through its builder (as the app builds it),
//! filling 90 open bars, and Generate on 90 bars (issue 26: the whole pipeline, every stage).

use std::cell::RefCell;
use std::sync::Arc;
use std::thread::LocalKey;

use odori_core::choreo::*;

thread_local! {
    static LIB: RefCell<Option<SegmentLibrary>> = const { RefCell::new(None) };
    static TABLE: RefCell<Option<Arc<TransitionTable>>> = const { RefCell::new(None) };
    static BUILDER: RefCell<Option<TableBuilder>> = const { RefCell::new(None) };
}

const REPEAT_PENALTY: f32 = 3.0;

/// Builds the built-in library once; returns its segment count.
#[no_mangle]
pub extern "C" fn build_builtin() -> u32 {
    SegmentLibrary::builtin().len() as u32
}

/// Builds the ≥ 2,000-segment library; returns its segment count.
#[no_mangle]
pub extern "C" fn setup() -> u32 {
    install(&LIB, odori_tests::builtin_medley_library())
}

/// Keeps `lib` in `slot` for the calls after; returns its segment count.
fn install(slot: &'static LocalKey<RefCell<Option<SegmentLibrary>>>, lib: SegmentLibrary) -> u32 {
    let m = lib.len() as u32;
    slot.with(|l| *l.borrow_mut() = Some(lib));
    m
}

/// Generate (every stage, default settings) on `odori_tests::bench_bars` from the library in
/// `slot`; returns the objective (-1 without a library).
fn generate90_from(slot: &'static LocalKey<RefCell<Option<SegmentLibrary>>>) -> f32 {
    slot.with(|l| {
        let lib = l.borrow();
        let Some(lib) = lib.as_ref() else { return -1.0 };
        odori_tests::generate_all(lib, &odori_tests::bench_bars()).1
    })
}

/// The transition table in one go (not cached between calls: a fresh library copy is not
/// needed, the table is rebuilt by [`TransitionTable::from_library`]). Returns its size.
#[no_mangle]
pub extern "C" fn table() -> u32 {
    LIB.with(|l| {
        let lib = l.borrow();
        let Some(lib) = lib.as_ref() else { return 0 };
        let t = Arc::new(TransitionTable::from_library(lib, REPEAT_PENALTY));
        let n = t.len() as u32;
        TABLE.with(|x| *x.borrow_mut() = Some(t));
        n
    })
}

/// Starts a sliced build of the table.
#[no_mangle]
pub extern "C" fn table_begin() -> u32 {
    LIB.with(|l| {
        let lib = l.borrow();
        let Some(lib) = lib.as_ref() else { return 0 };
        BUILDER.with(|b| *b.borrow_mut() = Some(lib.table_builder(REPEAT_PENALTY)));
        lib.len() as u32
    })
}

/// One slice of up to `columns` columns; returns the fraction done (-1 without a builder).
#[no_mangle]
pub extern "C" fn table_step(columns: u32) -> f32 {
    BUILDER.with(|b| b.borrow_mut().as_mut().map_or(-1.0, |b| b.step(columns as usize).fraction()))
}

/// Whether the sliced build equals the one-go table.
#[no_mangle]
pub extern "C" fn table_finish_matches() -> u32 {
    let built = BUILDER.with(|b| b.borrow_mut().take()).and_then(TableBuilder::finish);
    TABLE.with(|t| match (built, t.borrow().as_ref()) {
        (Some(a), Some(b)) => u32::from(a == **b),
        _ => 0,
    })
}

#[no_mangle]
pub extern "C" fn fill90() -> f32 {
    fill90_with(FillWeights { repeat_window: 1, ..FillWeights::default() })
}

#[no_mangle]
pub extern "C" fn fill90_default() -> f32 {
    fill90_with(FillWeights::default())
}

fn fill90_with(w: FillWeights) -> f32 {
    LIB.with(|l| {
        let lib = l.borrow();
        let Some(lib) = lib.as_ref() else { return -1.0 };
        let Some(t) = TABLE.with(|x| x.borrow().clone()) else { return -1.0 };
        let m = t.len();
        let inten: Vec<f32> = lib.segments().iter().map(|s| s.intensity01).collect();
        let layers = odori_tests::bench_layers(m);
        fill(&t, &layers, &inten, &w).map_or(-1.0, |r| r.1)
    })
}

/// Generate (every stage, default settings) on the 90 bars of `odori_tests::bench_bars` from the
/// ≥ 2,000-segment library (its transition table cached in the library after the first call, as
/// in the app); returns the dance's objective (-1 without a library).
#[no_mangle]
pub extern "C" fn generate90() -> f32 {
    generate90_from(&LIB)
}

thread_local! {
    static BUILTIN: RefCell<Option<SegmentLibrary>> = const { RefCell::new(None) };
    static OTHER: RefCell<Option<SegmentLibrary>> = const { RefCell::new(None) };
}

/// Builds the second library (`odori_tests::every_other_medley_library`: the built-in moves plus
/// a medley of every other built-in clip, cut at every count), so Generate's figure is not of
/// one library alone; returns its segment count.
#[no_mangle]
pub extern "C" fn setup_every_other() -> u32 {
    install(&OTHER, odori_tests::every_other_medley_library())
}

/// Generate as [`generate90`] from the second library ([`setup_every_other`]); returns the
/// objective (-1 without the library).
#[no_mangle]
pub extern "C" fn generate90_every_other() -> f32 {
    generate90_from(&OTHER)
}

thread_local! {
    static FILES: RefCell<Vec<(String, Vec<u8>)>> = const { RefCell::new(Vec::new()) };
    static REAL: RefCell<Option<SegmentLibrary>> = const { RefCell::new(None) };
}

/// Room for `len` bytes in the module's memory, for the host to write a file's name or bytes
/// into and hand over with [`real_add`].
#[no_mangle]
pub extern "C" fn bytes_alloc(len: u32) -> *mut u8 {
    let mut v = vec![0u8; len as usize];
    let p = v.as_mut_ptr();
    std::mem::forget(v);
    p
}

/// Keeps one real file for [`setup_real`]: its path relative to the data directory at
/// (`name_ptr`, `name_len`) and its bytes at (`ptr`, `len`); returns how many files are kept.
///
/// # Safety
/// Each pointer must come from [`bytes_alloc`] with that very length, and is taken over.
#[no_mangle]
pub unsafe extern "C" fn real_add(name_ptr: *mut u8, name_len: u32, ptr: *mut u8, len: u32) -> u32 {
    // SAFETY: the caller hands over two buffers bytes_alloc made with these lengths (a
    // vec![0; len], whose capacity is its length).
    let (name, bytes) = unsafe { (Vec::from_raw_parts(name_ptr, name_len as usize, name_len as usize), Vec::from_raw_parts(ptr, len as usize, len as usize)) };
    FILES.with(|f| {
        let mut f = f.borrow_mut();
        f.push((String::from_utf8_lossy(&name).into_owned(), bytes));
        f.len() as u32
    })
}

/// Builds the library of real files (`odori_tests::real_file_library`) from the files kept by
/// [`real_add`]; returns its segment count.
#[no_mangle]
pub extern "C" fn setup_real() -> u32 {
    let files = FILES.with(|f| std::mem::take(&mut *f.borrow_mut()));
    install(&REAL, odori_tests::real_file_library(&files))
}

/// Generate as [`generate90`] from the library of real files ([`setup_real`]); returns the
/// objective (-1 without the library).
#[no_mangle]
pub extern "C" fn generate90_real() -> f32 {
    generate90_from(&REAL)
}

/// Makes the library of real files the one [`generate90_profile`] and [`generate90_variant`]
/// run on (the medleys' dances need no refill); returns its segment count (0 without it).
#[no_mangle]
pub extern "C" fn real_as_main() -> u32 {
    match REAL.with(|r| r.borrow_mut().take()) {
        Some(lib) => install(&LIB, lib),
        None => 0,
    }
}

/// Generate on the same 90 bars from the built-in library alone (558 segments), where the
/// variety term is on (it is off while a library holds imported moves, as the medley is); the
/// library is built on the first call. Returns the objective.
#[no_mangle]
pub extern "C" fn generate90_builtin() -> f32 {
    BUILTIN.with(|b| {
        let mut b = b.borrow_mut();
        let lib = b.get_or_insert_with(SegmentLibrary::builtin);
        odori_tests::generate_all(lib, &odori_tests::bench_bars()).1
    })
}

// Issue 26's speed work: the same Generate at the default settings against the controls in the
// same run — session 15's measures (quick_measures off), the old pipeline (67f699e's settings:
// measure_played off, the order stage off), windowed refills (GenerateOptions::windowed_refills)
// and session 16's default (GenerateOptions::join_bans_at_once off) — and where the time goes per stage
// (odori_core::choreo::profile, on the host's clock).

#[link(wasm_import_module = "env")]
extern "C" {
    /// The host's `performance.now()`, milliseconds.
    fn now_ms() -> f64;
}

fn host_clock() -> f64 {
    // SAFETY: an import run.mjs provides; it reads the host's clock and touches no memory.
    unsafe { now_ms() }
}

thread_local! {
    static PROFILE: RefCell<Option<profile::Profile>> = const { RefCell::new(None) };
    static DANCES: RefCell<[Vec<Option<usize>>; 10]> = const { RefCell::new([Vec::new(), Vec::new(), Vec::new(), Vec::new(), Vec::new(), Vec::new(), Vec::new(), Vec::new(), Vec::new(), Vec::new()]) };
}

/// The settings of variant `v`: 0 the default, 1 windowed refills, 2 session 15's measures
/// (quick_measures off, the control), 3 the old pipeline (67f699e's settings: measured unheld,
/// no order stage), 4 session 16's default (one join barred a refill: join_bans_at_once off), 5
/// session 17's work (every top list tried whole, every frame of each held pass posed:
/// pose_read_frames_only off and session 18's fills), 6 session 18's work (top lists stopped by
/// the cheapest node of all: top_lists_stop_at_rest off), 7 session 19's work (whole columns
/// scanned entry by entry: columns_scanned_by_chunks off), 8 session 20's work (the held-feet
/// rule's free pass posing every joint: free_pass_legs_only off), 9 session 24's measures (every
/// round of the held-feet rule posed anew: rounds_copy_same_frames off, today's main, the control).
fn variant(v: u32) -> GenerateOptions {
    let d = GenerateOptions::default();
    match v {
        1 => GenerateOptions { windowed_refills: true, ..d },
        2 => GenerateOptions { quick_measures: false, ..d },
        3 => GenerateOptions { measure_played: false, follow_order: false, ..d },
        4 => GenerateOptions { join_bans_at_once: false, ..d },
        5 => GenerateOptions { pose_read_frames_only: false, top_lists_stop_at_rest: false, columns_scanned_by_chunks: false, ..d },
        6 => GenerateOptions { top_lists_stop_at_rest: false, columns_scanned_by_chunks: false, ..d },
        7 => GenerateOptions { columns_scanned_by_chunks: false, ..d },
        8 => GenerateOptions { free_pass_legs_only: false, ..d },
        9 => GenerateOptions { rounds_copy_same_frames: false, ..d },
        _ => d,
    }
}

fn generate90_with(v: u32) -> (Vec<Option<usize>>, f32) {
    LIB.with(|l| {
        let lib = l.borrow();
        let Some(lib) = lib.as_ref() else { return (Vec::new(), -1.0) };
        let o = variant(v);
        match generate_states(lib, &odori_tests::bench_bars(), &[], FillWeights::default(), &o) {
            Ok((states, r)) => (states.iter().map(BarState::segment).collect(), r.cost),
            Err(_) => (Vec::new(), -1.0),
        }
    })
}

/// Generate as [`generate90`] with the settings of variant `v` ([`variant`]); keeps the dance
/// for [`generate90_same`]. Returns the objective.
#[no_mangle]
pub extern "C" fn generate90_variant(v: u32) -> f32 {
    let (dance, cost) = generate90_with(v);
    DANCES.with(|d| {
        if let Some(slot) = d.borrow_mut().get_mut(v as usize) {
            *slot = dance;
        }
    });
    cost
}

/// Whether the last dances of variants `a` and `b` are the same (1), and else in how many bars
/// they differ (negative).
#[no_mangle]
pub extern "C" fn generate90_same(a: u32, b: u32) -> i32 {
    DANCES.with(|d| {
        let d = d.borrow();
        let (Some(x), Some(y)) = (d.get(a as usize), d.get(b as usize)) else { return 0 };
        let differ = x.iter().zip(y).filter(|(a, b)| a != b).count() + x.len().abs_diff(y.len());
        if differ == 0 { 1 } else { -(differ as i32) }
    })
}

/// One Generate profiled with the settings of variant `v`; read with [`profile_value`].
#[no_mangle]
pub extern "C" fn generate90_profile(v: u32) -> f32 {
    let ((_, cost), p) = profile::profiled(host_clock, || generate90_with(v));
    PROFILE.with(|x| *x.borrow_mut() = Some(p));
    cost
}

/// Of the last profile, stage `stage` (index into `profile::STAGES`): `field` 0 its total ms,
/// 1 fills, 2 fill ms, 3 measures, 4 measure ms (-1 when none).
#[no_mangle]
pub extern "C" fn profile_value(stage: u32, field: u32) -> f64 {
    PROFILE.with(|x| {
        let x = x.borrow();
        let Some(s) = x.as_ref().and_then(|p| p.stages.get(stage as usize)) else { return -1.0 };
        match field {
            0 => s.total_ms,
            1 => s.fills as f64,
            2 => s.fill_ms,
            3 => s.measures as f64,
            4 => s.measure_ms,
            _ => -1.0,
        }
    })
}

/// Of the last profile, part `k` of a measure (index into `profile::PARTS`): `field` 0 how many,
/// 1 its ms over every stage (-1 when none).
#[no_mangle]
pub extern "C" fn profile_part(k: u32, field: u32) -> f64 {
    PROFILE.with(|x| {
        let x = x.borrow();
        let Some(s) = x.as_ref().and_then(|p| p.parts.get(k as usize)) else { return -1.0 };
        match field {
            0 => s.count as f64,
            1 => s.ms,
            _ => -1.0,
        }
    })
}
