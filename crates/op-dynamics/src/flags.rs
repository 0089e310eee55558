//! Per-particle flags (seed 000 §6, seed 002 §5).

use serde::{Deserialize, Serialize};

/// A small bit set of per-particle flags.
#[derive(
    Copy, Clone, Default, PartialEq, Eq, Hash, Debug, Serialize, Deserialize, schemars::JsonSchema,
)]
#[serde(transparent)]
pub struct Flags(u8);

impl Flags {
    /// The particle's position is fixed (it never translates).
    pub const FIXED_POSITION: Flags = Flags(1);
    /// The particle's orientation is fixed (it never rotates).
    pub const FIXED_ORIENTATION: Flags = Flags(2);
    /// The particle has no orientation: it keeps spacing forces and drops
    /// every orientation term (seed 000 §6, creases).
    pub const UNORIENTED: Flags = Flags(4);

    /// No flag set.
    pub const fn empty() -> Self {
        Flags(0)
    }
    /// True when every flag of `other` is set in `self`.
    pub const fn contains(self, other: Flags) -> bool {
        self.0 & other.0 == other.0
    }
    /// Sets the flags of `other`.
    pub fn insert(&mut self, other: Flags) {
        self.0 |= other.0;
    }
    /// Clears the flags of `other`.
    pub fn remove(&mut self, other: Flags) {
        self.0 &= !other.0;
    }
    /// The union of two flag sets.
    pub const fn union(self, other: Flags) -> Flags {
        Flags(self.0 | other.0)
    }
    /// The raw bits.
    pub const fn bits(self) -> u8 {
        self.0
    }
}

impl std::ops::BitOr for Flags {
    type Output = Flags;
    fn bitor(self, rhs: Flags) -> Flags {
        self.union(rhs)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn insert_remove_contains() {
        let mut f = Flags::empty();
        assert!(!f.contains(Flags::FIXED_POSITION));
        f.insert(Flags::FIXED_POSITION | Flags::UNORIENTED);
        assert!(f.contains(Flags::FIXED_POSITION));
        assert!(f.contains(Flags::UNORIENTED));
        assert!(!f.contains(Flags::FIXED_ORIENTATION));
        f.remove(Flags::FIXED_POSITION);
        assert!(!f.contains(Flags::FIXED_POSITION));
        assert!(f.contains(Flags::empty()));
    }
}
