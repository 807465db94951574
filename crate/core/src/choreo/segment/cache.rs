//! The transition table (spec §G) a library keeps: built once per library and repetition
//! penalty (or block by block, for the metres a song needs), shared by copies of the library,
//! dropped when its segments change (each change gives the library a new revision, so a table
//! built for another revision is refused).

use std::sync::{Arc, Mutex};

use super::super::table::{TableBuilder, TableScope, TransitionTable};
use super::SegmentLibrary;

/// A copy shares the cached transition table (it is immutable behind its `Arc`): a project
/// keeps the built-in library once and starts each rebuild from a copy of it, instead of
/// making the 420 moves again (1–2 s in a browser tab).
impl Clone for SegmentLibrary {
    fn clone(&self) -> Self {
        let table = match self.table.lock() {
            Ok(g) => g.clone(),
            Err(poisoned) => poisoned.into_inner().clone(),
        };
        SegmentLibrary {
            clips: self.clips.clone(),
            segments: self.segments.clone(),
            signatures: self.signatures.clone(),
            ends: self.ends.clone(),
            overlaps: self.overlaps.clone(),
            table: Mutex::new(table),
            revision: self.revision,
        }
    }
}

impl SegmentLibrary {
    /// Drops the cached table and gives the library a new revision, unique in the process
    /// (libraries copied from one another then never share a revision once they differ, so a
    /// table built for one is refused by the other).
    pub(super) fn changed(&mut self) {
        static NEXT_REVISION: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(1);
        self.revision = NEXT_REVISION.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        if let Ok(mut t) = self.table.lock() {
            *t = None;
        }
    }

    /// Changes with every change of the segments.
    pub fn revision(&self) -> u64 {
        self.revision
    }

    /// A builder of this library's all-pairs transition table, to run in slices (see
    /// [`TableBuilder`]); hand its result to [`SegmentLibrary::install_table`].
    pub fn table_builder(&self, repeat_penalty: f32) -> TableBuilder {
        TableBuilder::new(self, repeat_penalty)
    }

    /// A builder of the blocks of `scope` ([`TableScope`]: what a song's bars need,
    /// [`TableScope::for_bar_counts`]) that the cached table (same penalty) lacks; its
    /// table holds the cached blocks too. Hand its result to
    /// [`SegmentLibrary::install_table_for`].
    pub fn table_builder_for(&self, repeat_penalty: f32, scope: &TableScope) -> TableBuilder {
        let cached = self.cached_table(repeat_penalty);
        TableBuilder::for_scope(self, repeat_penalty, scope, cached.as_deref())
    }

    /// Caches a table built by [`SegmentLibrary::table_builder`] or
    /// [`SegmentLibrary::table_builder_for`]; refused (`false`) when the library changed since
    /// (another revision, or segments grouped by other metres).
    pub fn install_table(&self, table: TransitionTable) -> bool {
        if table.revision() != self.revision || table.len() != self.len() {
            return false;
        }
        if !table.scope().is_all_pairs() && table.metres() != super::super::table::library_metres(self).as_slice() {
            return false;
        }
        let mut guard = match self.table.lock() {
            Ok(g) => g,
            Err(poisoned) => poisoned.into_inner(),
        };
        *guard = Some(Arc::new(table));
        true
    }

    /// [`SegmentLibrary::install_table`], refused too when the table lacks a block of `scope`
    /// (built for another set of metres than the song now needs).
    pub fn install_table_for(&self, table: TransitionTable, scope: &TableScope) -> bool {
        table.scope().covers(scope) && self.install_table(table)
    }

    /// Drops the cached table (its memory is freed once no one holds it); the next one needed
    /// is built again.
    pub fn drop_table(&self) {
        if let Ok(mut t) = self.table.lock() {
            *t = None;
        }
    }

    /// The cached table, when there is one for this repetition penalty.
    pub fn cached_table(&self, repeat_penalty: f32) -> Option<Arc<TransitionTable>> {
        let guard = self.table.lock().ok()?;
        guard.as_ref().filter(|t| t.repeat_penalty() == repeat_penalty).cloned()
    }

    /// The cached table, when there is one for this repetition penalty holding every pair of
    /// `scope`.
    pub fn cached_table_for(&self, repeat_penalty: f32, scope: &TableScope) -> Option<Arc<TransitionTable>> {
        self.cached_table(repeat_penalty).filter(|t| t.scope().covers(scope))
    }

    /// The all-pairs transition table of spec §G for this library with the given repetition
    /// penalty (built once per library and penalty, then shared), reporting progress (0..1);
    /// the callback returns `false` to cancel (then `None`, and nothing is cached).
    pub fn transition_table_with_progress(&self, repeat_penalty: f32, progress: &mut dyn FnMut(f32) -> bool) -> Option<Arc<TransitionTable>> {
        if let Some(t) = self.cached_table_for(repeat_penalty, &TableScope::all_pairs()) {
            return Some(t);
        }
        let t = Arc::new(TransitionTable::from_library_with_progress(self, repeat_penalty, progress)?);
        if let Ok(mut guard) = self.table.lock() {
            *guard = Some(t.clone());
        }
        Some(t)
    }

    /// The all-pairs transition table of spec §G for this library with the given repetition
    /// penalty (built once per library and penalty, then shared).
    pub fn transition_table(&self, repeat_penalty: f32) -> Arc<TransitionTable> {
        self.transition_table_for(repeat_penalty, &TableScope::all_pairs())
    }

    /// A transition table holding (at least) the pairs of `scope` ([`TableScope`]): the cached
    /// one when it does; else one built with the blocks missing from the cached one (same
    /// penalty) added, then cached.
    pub fn transition_table_for(&self, repeat_penalty: f32, scope: &TableScope) -> Arc<TransitionTable> {
        let mut guard = match self.table.lock() {
            Ok(g) => g,
            Err(poisoned) => poisoned.into_inner(),
        };
        let cached = guard.as_ref().filter(|t| t.repeat_penalty() == repeat_penalty).cloned();
        if let Some(t) = cached.as_ref().filter(|t| t.scope().covers(scope)) {
            return t.clone();
        }
        let mut b = TableBuilder::for_scope(self, repeat_penalty, scope, cached.as_deref());
        while !b.step(usize::MAX).is_done() {}
        let t = Arc::new(b.finish().unwrap_or_else(|| TransitionTable::from_library(self, repeat_penalty)));
        *guard = Some(t.clone());
        t
    }
}
