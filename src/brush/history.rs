//! Undo/redo over material states. Every change pushes the new state; undo and redo move a cursor.
//! A push after an undo drops the redo branch, as every editor does.

use crate::brdf::Material;

/// States kept before the oldest is dropped.
pub const HISTORY_LIMIT: usize = 1000;

#[derive(Clone, Debug)]
pub struct History {
    states: Vec<Material>,
    cursor: usize,
    generation: u64,
}

impl History {
    pub fn new(initial: Material) -> Self {
        History { states: vec![initial], cursor: 0, generation: 0 }
    }

    pub fn current(&self) -> &Material {
        &self.states[self.cursor]
    }

    /// Changes whenever the current material may have changed (push, amend, undo, redo): what a
    /// view compares to know it must re-render, instead of comparing materials.
    pub fn generation(&self) -> u64 {
        self.generation
    }

    /// Records a new state (nothing when it equals the current one).
    pub fn push(&mut self, m: Material) {
        if *self.current() == m {
            return;
        }
        self.states.truncate(self.cursor + 1);
        self.states.push(m);
        if self.states.len() > HISTORY_LIMIT {
            self.states.remove(0);
        }
        self.cursor = self.states.len() - 1;
        self.generation += 1;
    }

    /// Replaces the current state without a new undo step (a slider still being dragged: the whole
    /// drag is one step).
    pub fn amend(&mut self, m: Material) {
        self.states.truncate(self.cursor + 1);
        self.states[self.cursor] = m;
        self.generation += 1;
    }

    pub fn can_undo(&self) -> bool {
        self.cursor > 0
    }

    pub fn can_redo(&self) -> bool {
        self.cursor + 1 < self.states.len()
    }

    /// Steps back; `false` when there is nothing to undo.
    pub fn undo(&mut self) -> bool {
        let ok = self.can_undo();
        if ok {
            self.cursor -= 1;
            self.generation += 1;
        }
        ok
    }

    /// Steps forward; `false` when there is nothing to redo.
    pub fn redo(&mut self) -> bool {
        let ok = self.can_redo();
        if ok {
            self.cursor += 1;
            self.generation += 1;
        }
        ok
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn with_diffuse(d: f64) -> Material {
        Material { diffuse: [d; 3], ..Material::scratch() }
    }

    #[test]
    fn undo_redo_and_branching() {
        let mut h = History::new(with_diffuse(0.1));
        h.push(with_diffuse(0.2));
        h.push(with_diffuse(0.3));
        assert!(h.undo());
        assert_eq!(h.current().diffuse[0], 0.2);
        assert!(h.undo());
        assert!(!h.undo());
        assert_eq!(h.current().diffuse[0], 0.1);
        assert!(h.redo());
        assert_eq!(h.current().diffuse[0], 0.2);
        h.push(with_diffuse(0.4));
        assert!(!h.redo(), "a new change drops the redo branch");
        assert!(h.undo());
        assert_eq!(h.current().diffuse[0], 0.2);
    }

    #[test]
    fn identical_state_is_not_recorded_and_limit_holds() {
        let mut h = History::new(with_diffuse(0.0));
        h.push(with_diffuse(0.0));
        assert!(!h.can_undo());
        for i in 0..HISTORY_LIMIT + 10 {
            h.push(with_diffuse(i as f64 * 1e-4));
        }
        let mut n = 0;
        while h.undo() {
            n += 1;
        }
        assert_eq!(n, HISTORY_LIMIT - 1);
    }
}
