//! A vector that keeps up to `N` items inline and moves to the heap beyond: the storage of
//! every per-block list of the world ([`State`](crate::State)'s cells, [`Goal`](crate::Goal)'s
//! order, [`ActionMask`](crate::ActionMask)'s bits).
//!
//! The paper's world has at most 16 blocks, and its states are cloned and hashed millions of
//! times a second by the planners and learners: there a state must cost no allocation. The
//! side view plays thousands of blocks, where a fixed array of the largest size would cost
//! every small state megabytes. So a list of at most `N` items lives in an array inside the
//! value (a clone is a copy, no allocation), and a longer one in a `Vec` (O(items) memory).
//! Equality, ordering and hashing see only the items, never where they are kept.
//!
//! Written here rather than taken from a crate: it is a few dozen lines of safe code, and
//! the items it holds are small `Copy` values (cells, block ids, bit words), which a
//! default-filled array can hold without `unsafe`.

use std::fmt;
use std::hash::{Hash, Hasher};
use std::ops::{Deref, DerefMut};

/// Up to `N` items inline, more on the heap (module docs). Behaves as a `Vec<T>` through
/// its slice ([`Deref`]) and [`InlineVec::push`], [`InlineVec::pop`], [`InlineVec::truncate`].
#[derive(Clone)]
pub struct InlineVec<T: Copy + Default, const N: usize>(Repr<T, N>);

#[derive(Clone)]
enum Repr<T: Copy + Default, const N: usize> {
    /// `items[..len]` are the items; the rest stay at their default.
    Inline { len: u16, items: [T; N] },
    /// More than `N` items (or once were: a heap vector that shrinks stays on the heap).
    Heap(Vec<T>),
}

impl<T: Copy + Default, const N: usize> InlineVec<T, N> {
    // The inline length is a u16.
    const FITS: () = assert!(N <= u16::MAX as usize);

    /// An empty vector (inline).
    #[inline]
    pub fn new() -> Self {
        let () = Self::FITS;
        InlineVec(Repr::Inline {
            len: 0,
            items: [T::default(); N],
        })
    }

    /// The items of `items`, inline when there are at most `N`.
    #[inline]
    pub fn from_slice(items: &[T]) -> Self {
        if items.len() <= N {
            let mut inline = [T::default(); N];
            inline[..items.len()].copy_from_slice(items);
            InlineVec(Repr::Inline {
                len: items.len() as u16,
                items: inline,
            })
        } else {
            InlineVec(Repr::Heap(items.to_vec()))
        }
    }

    /// `len` copies of `value`.
    #[inline]
    pub fn from_elem(value: T, len: usize) -> Self {
        if len <= N {
            let mut items = [T::default(); N];
            items[..len].fill(value);
            InlineVec(Repr::Inline { len: len as u16, items })
        } else {
            InlineVec(Repr::Heap(vec![value; len]))
        }
    }

    /// Number of items.
    #[inline]
    pub fn len(&self) -> usize {
        match &self.0 {
            Repr::Inline { len, .. } => usize::from(*len),
            Repr::Heap(v) => v.len(),
        }
    }

    /// Whether there are no items.
    #[inline]
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Whether the items are kept inline (no heap allocation).
    #[inline]
    pub fn is_inline(&self) -> bool {
        matches!(self.0, Repr::Inline { .. })
    }

    /// The items.
    #[inline]
    pub fn as_slice(&self) -> &[T] {
        match &self.0 {
            Repr::Inline { len, items } => &items[..usize::from(*len)],
            Repr::Heap(v) => v,
        }
    }

    /// The items, mutably.
    #[inline]
    pub fn as_mut_slice(&mut self) -> &mut [T] {
        match &mut self.0 {
            Repr::Inline { len, items } => &mut items[..usize::from(*len)],
            Repr::Heap(v) => v,
        }
    }

    /// Appends `value`, moving the items to the heap when they no longer fit inline.
    #[inline]
    pub fn push(&mut self, value: T) {
        match &mut self.0 {
            Repr::Inline { len, items } if usize::from(*len) < N => {
                items[usize::from(*len)] = value;
                *len += 1;
            }
            Repr::Inline { items, .. } => {
                let mut v = Vec::with_capacity(2 * N + 1);
                v.extend_from_slice(items);
                v.push(value);
                self.0 = Repr::Heap(v);
            }
            Repr::Heap(v) => v.push(value),
        }
    }

    /// Removes and returns the last item, if any.
    #[inline]
    pub fn pop(&mut self) -> Option<T> {
        match &mut self.0 {
            Repr::Inline { len: 0, .. } => None,
            Repr::Inline { len, items } => {
                *len -= 1;
                Some(std::mem::take(&mut items[usize::from(*len)]))
            }
            Repr::Heap(v) => v.pop(),
        }
    }

    /// Keeps the first `len` items (nothing changes if there are no more).
    #[inline]
    pub fn truncate(&mut self, new_len: usize) {
        match &mut self.0 {
            Repr::Inline { len, items } => {
                if new_len < usize::from(*len) {
                    // Unused slots stay at their default.
                    items[new_len..usize::from(*len)].fill(T::default());
                    *len = new_len as u16;
                }
            }
            Repr::Heap(v) => v.truncate(new_len),
        }
    }

    /// Removes every item.
    #[inline]
    pub fn clear(&mut self) {
        self.truncate(0);
    }
}

impl<T: Copy + Default, const N: usize> Default for InlineVec<T, N> {
    fn default() -> Self {
        Self::new()
    }
}

impl<T: Copy + Default, const N: usize> Deref for InlineVec<T, N> {
    type Target = [T];

    #[inline]
    fn deref(&self) -> &[T] {
        self.as_slice()
    }
}

impl<T: Copy + Default, const N: usize> DerefMut for InlineVec<T, N> {
    #[inline]
    fn deref_mut(&mut self) -> &mut [T] {
        self.as_mut_slice()
    }
}

impl<T: Copy + Default + PartialEq, const N: usize> PartialEq for InlineVec<T, N> {
    #[inline]
    fn eq(&self, other: &Self) -> bool {
        self.as_slice() == other.as_slice()
    }
}

impl<T: Copy + Default + Eq, const N: usize> Eq for InlineVec<T, N> {}

impl<T: Copy + Default + Hash, const N: usize> Hash for InlineVec<T, N> {
    #[inline]
    fn hash<H: Hasher>(&self, state: &mut H) {
        self.as_slice().hash(state);
    }
}

impl<T: Copy + Default + PartialOrd, const N: usize> PartialOrd for InlineVec<T, N> {
    fn partial_cmp(&self, other: &Self) -> Option<std::cmp::Ordering> {
        self.as_slice().partial_cmp(other.as_slice())
    }
}

impl<T: Copy + Default + Ord, const N: usize> Ord for InlineVec<T, N> {
    fn cmp(&self, other: &Self) -> std::cmp::Ordering {
        self.as_slice().cmp(other.as_slice())
    }
}

impl<T: Copy + Default + fmt::Debug, const N: usize> fmt::Debug for InlineVec<T, N> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        self.as_slice().fmt(f)
    }
}

impl<T: Copy + Default, const N: usize> FromIterator<T> for InlineVec<T, N> {
    fn from_iter<I: IntoIterator<Item = T>>(iter: I) -> Self {
        let mut out = InlineVec::new();
        out.extend(iter);
        out
    }
}

impl<T: Copy + Default, const N: usize> Extend<T> for InlineVec<T, N> {
    fn extend<I: IntoIterator<Item = T>>(&mut self, iter: I) {
        for item in iter {
            self.push(item);
        }
    }
}

impl<'a, T: Copy + Default, const N: usize> IntoIterator for &'a InlineVec<T, N> {
    type Item = &'a T;
    type IntoIter = std::slice::Iter<'a, T>;

    fn into_iter(self) -> Self::IntoIter {
        self.as_slice().iter()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// One operation of the model test.
    #[derive(Clone, Debug)]
    enum Op {
        Push(u16),
        Pop,
        Truncate(usize),
        Set(usize, u16),
        Clear,
        Extend(Vec<u16>),
    }

    fn op() -> impl Strategy<Value = Op> {
        prop_oneof![
            4 => any::<u16>().prop_map(Op::Push),
            2 => Just(Op::Pop),
            1 => (0usize..12).prop_map(Op::Truncate),
            2 => (0usize..12, any::<u16>()).prop_map(|(i, v)| Op::Set(i, v)),
            1 => Just(Op::Clear),
            1 => proptest::collection::vec(any::<u16>(), 0..8).prop_map(Op::Extend),
        ]
    }

    proptest! {
        /// Every sequence of operations leaves the same items as a `Vec` given the same
        /// operations, inline while they fit.
        #[test]
        fn behaves_as_a_vec(start in proptest::collection::vec(any::<u16>(), 0..10), ops in proptest::collection::vec(op(), 0..60)) {
            let mut model = start.clone();
            let mut v: InlineVec<u16, 4> = InlineVec::from_slice(&start);
            prop_assert_eq!(v.is_inline(), start.len() <= 4);
            for op in ops {
                match op {
                    Op::Push(x) => { model.push(x); v.push(x); }
                    Op::Pop => prop_assert_eq!(v.pop(), model.pop()),
                    Op::Truncate(n) => { model.truncate(n); v.truncate(n); }
                    Op::Set(i, x) => if i < model.len() { model[i] = x; v[i] = x; },
                    Op::Clear => { model.clear(); v.clear(); }
                    Op::Extend(xs) => { model.extend(&xs); v.extend(xs); }
                }
                prop_assert_eq!(v.as_slice(), model.as_slice());
                prop_assert_eq!(v.len(), model.len());
                prop_assert_eq!(v.is_empty(), model.is_empty());
                if model.len() > 4 {
                    prop_assert!(!v.is_inline());
                }
            }
            // Equality, order and hashing see the items only, inline or not.
            let rebuilt: InlineVec<u16, 4> = model.iter().copied().collect();
            prop_assert_eq!(&rebuilt, &v);
            prop_assert_eq!(rebuilt.cmp(&v), std::cmp::Ordering::Equal);
            let hasher = std::collections::hash_map::RandomState::new();
            {
                use std::hash::BuildHasher;
                prop_assert_eq!(hasher.hash_one(&rebuilt), hasher.hash_one(&v));
                prop_assert_eq!(hasher.hash_one(&rebuilt), hasher.hash_one(model.as_slice()));
            }
            prop_assert_eq!(format!("{v:?}"), format!("{model:?}"));
            let sevens = InlineVec::<u16, 4>::from_elem(7, model.len());
            prop_assert_eq!(sevens.to_vec(), vec![7; model.len()]);
        }
    }

    #[test]
    fn small_lists_stay_inline_and_large_ones_move_to_the_heap() {
        let mut v: InlineVec<u8, 16> = (0..16).collect();
        assert!(v.is_inline());
        v.push(16);
        assert!(!v.is_inline());
        assert_eq!(v.len(), 17);
        assert_eq!(v.pop(), Some(16));
        assert_eq!(v, (0..16).collect::<InlineVec<u8, 16>>());
    }
}
