//! Disjoint sets (union-find) over `0..n`, for the connected pieces the
//! triangulation and the fit count (mesh pieces, boundary loops, fans,
//! thin features, chains of boundary samples) and those of a scene's
//! objects (op-scene's health watch).

/// Disjoint sets of `0..n` with path halving; a set's root is its
/// smallest member, so roots, and everything ordered by them, do not
/// depend on the order of the unions.
pub struct DisjointSets {
    parent: Vec<usize>,
}

impl DisjointSets {
    /// `n` singletons.
    pub fn new(n: usize) -> Self {
        DisjointSets {
            parent: (0..n).collect(),
        }
    }

    /// The root (smallest member) of `x`'s set.
    pub fn root(&mut self, mut x: usize) -> usize {
        while self.parent[x] != x {
            self.parent[x] = self.parent[self.parent[x]];
            x = self.parent[x];
        }
        x
    }

    /// Joins the sets of `a` and `b`; whether they were apart.
    pub fn union(&mut self, a: usize, b: usize) -> bool {
        let (ra, rb) = (self.root(a), self.root(b));
        self.parent[ra.max(rb)] = ra.min(rb);
        ra != rb
    }

    /// Number of sets.
    pub fn count(&mut self) -> usize {
        (0..self.parent.len())
            .filter(|&x| self.root(x) == x)
            .count()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Unions in any order give the smallest member as root.
    #[test]
    fn roots_are_smallest_members() {
        let mut s = DisjointSets::new(6);
        assert!(s.union(4, 2));
        assert!(s.union(5, 4));
        assert!(!s.union(2, 5));
        assert!(s.union(3, 1));
        assert_eq!(
            (0..6).map(|x| s.root(x)).collect::<Vec<_>>(),
            [0, 1, 2, 1, 2, 2]
        );
        assert_eq!(s.count(), 3);
    }
}
