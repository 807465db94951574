//! Undo/redo by snapshots: the one history both the dance document (`choreo::document`) and
//! the project (`project`) keep. An edit records the state it replaces; undo and redo swap
//! the current state with the top of the other stack. Snapshots are whole documents (they
//! are small and cloning them is cheap next to deriving anything from them).

/// Past and undone states of a document of type `T`, oldest first.
/// Serialised as two fields, `undo` and `redo` (flattened into its owner, as before it existed).
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct History<T> {
    pub(crate) undo: Vec<T>,
    pub(crate) redo: Vec<T>,
}

impl<T> Default for History<T> {
    fn default() -> Self {
        History { undo: Vec::new(), redo: Vec::new() }
    }
}

impl<T> History<T> {
    /// A history restored from saved stacks.
    pub fn from_parts(undo: Vec<T>, redo: Vec<T>) -> Self {
        History { undo, redo }
    }

    /// Records `prev`, the state an edit replaced, keeping at most `limit` undo steps (the
    /// oldest is dropped first); an edit forgets what was undone.
    pub fn record(&mut self, prev: T, limit: usize) {
        self.undo.push(prev);
        if self.undo.len() > limit {
            self.undo.remove(0);
        }
        self.redo.clear();
    }

    /// Steps `current` back one edit; `false` when there is none.
    pub fn undo(&mut self, current: &mut T) -> bool {
        match self.undo.pop() {
            Some(prev) => {
                self.redo.push(std::mem::replace(current, prev));
                true
            }
            None => false,
        }
    }

    /// Steps `current` forward one undone edit; `false` when there is none.
    pub fn redo(&mut self, current: &mut T) -> bool {
        match self.redo.pop() {
            Some(next) => {
                self.undo.push(std::mem::replace(current, next));
                true
            }
            None => false,
        }
    }

    pub fn can_undo(&self) -> bool {
        !self.undo.is_empty()
    }

    pub fn can_redo(&self) -> bool {
        !self.redo.is_empty()
    }
}

#[cfg(test)]
mod tests {
    use super::History;

    #[test]
    fn undo_redo_walk_and_an_edit_forgets_the_redo_stack() {
        let mut h = History::default();
        let mut doc = 0;
        for next in 1..=3 {
            h.record(std::mem::replace(&mut doc, next), 2);
        }
        // Limit 2: only the last two steps can be undone.
        assert!(h.undo(&mut doc) && doc == 2);
        assert!(h.undo(&mut doc) && doc == 1);
        assert!(!h.undo(&mut doc) && doc == 1);
        assert!(h.redo(&mut doc) && doc == 2);
        h.record(std::mem::replace(&mut doc, 9), 2);
        assert!(!h.can_redo() && !h.redo(&mut doc) && doc == 9);
        assert!(h.undo(&mut doc) && doc == 2);
    }
}
