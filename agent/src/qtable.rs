//! The Q-table: one row of action values per key, dense where the keys can be indexed
//! within a memory budget, a hash map of the rows met so far where not.
//!
//! A table may also remember which entries were ever written (*seen*): the authors'
//! learner stored only the actions it had taken in a state and bootstrapped from the best
//! of those ([`Schedule::PaperCode`](crate::schedule::Schedule::PaperCode)). A table made
//! by [`QTable::new`] does not track them, and computes and stores exactly what it did
//! before tracking existed; [`QTable::tracking_seen`] makes one that does.

use std::collections::HashMap;

/// The most entries (keys x columns) a dense table may have: 2^24 `f32`s, 64 MiB. Beyond
/// it the table keeps only the rows it has met, in a hash map.
pub const DENSE_LIMIT: u64 = 1 << 24;

/// Q-values, `columns` per key; rows never written read as `initial`.
///
/// Two tables are equal when they hold the same values for every key, however stored, and
/// the same seen entries (module docs).
#[derive(Clone, Debug)]
pub struct QTable {
    key_count: u64,
    columns: usize,
    initial: f32,
    store: Store,
    /// The seen entries, when the table tracks them: per key, bit `c` for column `c`.
    seen: Option<Seen>,
}

/// Which entries were ever written, laid out like the values.
#[derive(Clone, Debug, PartialEq, Eq)]
enum Seen {
    /// Entry `k`: the seen columns of key `k`.
    Dense(Vec<u32>),
    /// The keys with a seen column.
    Sparse(HashMap<u64, u32>),
}

#[derive(Clone, Debug)]
enum Store {
    /// Row `k` is `values[k * columns..(k + 1) * columns]`.
    Dense(Vec<f32>),
    /// Rows met so far; `default_row` (all `initial`) stands for the others.
    Sparse {
        rows: HashMap<u64, Box<[f32]>>,
        default_row: Box<[f32]>,
    },
}

impl QTable {
    /// A table for keys `0..key_count` with `columns` actions, every value `initial`; dense
    /// when `key_count * columns <= DENSE_LIMIT`.
    pub fn new(key_count: u64, columns: usize, initial: f32) -> QTable {
        let entries = key_count.checked_mul(columns as u64);
        let store = match entries {
            Some(e) if e <= DENSE_LIMIT => Store::Dense(vec![initial; e as usize]),
            _ => Store::Sparse {
                rows: HashMap::new(),
                default_row: vec![initial; columns].into_boxed_slice(),
            },
        };
        QTable {
            key_count,
            columns,
            initial,
            store,
            seen: None,
        }
    }

    /// A table like [`QTable::new`]'s that also remembers which entries were ever written
    /// (at most 32 columns, as every world has).
    pub fn tracking_seen(key_count: u64, columns: usize, initial: f32) -> QTable {
        let mut table = QTable::new(key_count, columns, initial);
        table.track_seen();
        table
    }

    /// From now on, remembers which entries are written (none is seen yet); nothing for a
    /// table that does already.
    pub(crate) fn track_seen(&mut self) {
        debug_assert!(self.columns <= 32);
        if self.seen.is_none() {
            self.seen = Some(match self.store {
                Store::Dense(_) => Seen::Dense(vec![0; self.key_count as usize]),
                Store::Sparse { .. } => Seen::Sparse(HashMap::new()),
            });
        }
    }

    /// Whether the table remembers which entries were written.
    pub fn tracks_seen(&self) -> bool {
        self.seen.is_some()
    }

    /// The seen columns of `key` as bits (bit `c`: column `c`); 0 for a table that does not
    /// track them.
    #[inline]
    pub fn seen_columns(&self, key: u64) -> u32 {
        match &self.seen {
            None => 0,
            Some(Seen::Dense(bits)) => bits[key as usize],
            Some(Seen::Sparse(map)) => map.get(&key).copied().unwrap_or(0),
        }
    }

    /// Marks the entry `(key, column)` seen (nothing for a table that does not track them).
    #[inline]
    pub fn mark_seen(&mut self, key: u64, column: usize) {
        match &mut self.seen {
            None => {}
            Some(Seen::Dense(bits)) => bits[key as usize] |= 1 << column,
            Some(Seen::Sparse(map)) => *map.entry(key).or_insert(0) |= 1 << column,
        }
    }

    /// The largest value among the seen entries of `key`, `None` if none is seen.
    #[inline]
    pub fn seen_max(&self, key: u64) -> Option<f32> {
        let mut bits = self.seen_columns(key);
        let row = self.row(key);
        let mut best: Option<f32> = None;
        while bits != 0 {
            let c = bits.trailing_zeros() as usize;
            bits &= bits - 1;
            best = Some(best.map_or(row[c], |b| b.max(row[c])));
        }
        best
    }

    /// The keys with a seen entry and their seen columns, by increasing key (what a model
    /// file keeps); empty for a table that does not track them.
    pub fn seen_entries(&self) -> Vec<(u64, u32)> {
        match &self.seen {
            None => Vec::new(),
            Some(Seen::Dense(bits)) => bits
                .iter()
                .enumerate()
                .filter(|&(_, &b)| b != 0)
                .map(|(k, &b)| (k as u64, b))
                .collect(),
            Some(Seen::Sparse(map)) => {
                let mut out: Vec<(u64, u32)> = map.iter().filter(|&(_, &b)| b != 0).map(|(&k, &b)| (k, b)).collect();
                out.sort_unstable_by_key(|&(k, _)| k);
                out
            }
        }
    }

    /// A dense table whose row `k` is `values[k * columns..(k + 1) * columns]` (as
    /// [`QTable::new`] would make it dense: `key_count * columns <= DENSE_LIMIT`, and
    /// `values` holds exactly that many).
    pub(crate) fn from_dense(key_count: u64, columns: usize, initial: f32, values: Vec<f32>) -> QTable {
        debug_assert!(key_count * columns as u64 <= DENSE_LIMIT && values.len() as u64 == key_count * columns as u64);
        QTable {
            key_count,
            columns,
            initial,
            store: Store::Dense(values),
            seen: None,
        }
    }

    /// Number of keys (rows that may exist).
    pub fn key_count(&self) -> u64 {
        self.key_count
    }

    /// Number of columns (actions).
    pub fn columns(&self) -> usize {
        self.columns
    }

    /// The value of rows never written.
    pub fn initial(&self) -> f32 {
        self.initial
    }

    /// Whether the table is a dense array (otherwise a hash map of rows).
    pub fn is_dense(&self) -> bool {
        matches!(self.store, Store::Dense(_))
    }

    /// The row of `key` (`key < key_count()`).
    #[inline]
    pub fn row(&self, key: u64) -> &[f32] {
        debug_assert!(key < self.key_count);
        match &self.store {
            Store::Dense(values) => {
                let start = key as usize * self.columns;
                &values[start..start + self.columns]
            }
            Store::Sparse { rows, default_row } => rows.get(&key).map_or(default_row, |r| r),
        }
    }

    /// The row of `key`, to write (`key < key_count()`).
    #[inline]
    pub fn row_mut(&mut self, key: u64) -> &mut [f32] {
        debug_assert!(key < self.key_count);
        match &mut self.store {
            Store::Dense(values) => {
                let start = key as usize * self.columns;
                &mut values[start..start + self.columns]
            }
            Store::Sparse { rows, default_row } => rows.entry(key).or_insert_with(|| default_row.clone()),
        }
    }

    /// The rows that differ from the initial row, by increasing key: what a model file
    /// keeps.
    pub fn written_rows(&self) -> Vec<(u64, &[f32])> {
        let initial = self.initial;
        let changed = |row: &[f32]| row.iter().any(|v| v.to_bits() != initial.to_bits());
        match &self.store {
            Store::Dense(values) => values
                .chunks_exact(self.columns)
                .enumerate()
                .filter(|(_, row)| changed(row))
                .map(|(k, row)| (k as u64, row))
                .collect(),
            Store::Sparse { rows, .. } => {
                let mut out: Vec<(u64, &[f32])> = rows
                    .iter()
                    .filter(|(_, r)| changed(r))
                    .map(|(&k, r)| (k, &r[..]))
                    .collect();
                out.sort_unstable_by_key(|&(k, _)| k);
                out
            }
        }
    }
}

impl PartialEq for QTable {
    fn eq(&self, other: &QTable) -> bool {
        let same_shape = self.key_count == other.key_count
            && self.columns == other.columns
            && self.initial.to_bits() == other.initial.to_bits();
        same_shape
            && match (&self.store, &other.store) {
                (Store::Dense(a), Store::Dense(b)) => a == b,
                _ => self.written_rows() == other.written_rows(),
            }
            && self.tracks_seen() == other.tracks_seen()
            && self.seen_entries() == other.seen_entries()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn seen_entries_are_remembered_dense_and_sparse() {
        // 100 keys x 8 columns is dense; 2^40 keys is not.
        for keys in [100, 1 << 40] {
            let mut t = QTable::tracking_seen(keys, 8, 0.0);
            assert!(t.tracks_seen());
            assert_eq!(t.seen_max(7), None);
            t.row_mut(7)[3] = -2.0;
            t.mark_seen(7, 3);
            assert_eq!(t.seen_max(7), Some(-2.0), "the unseen zeros do not count");
            t.mark_seen(7, 5);
            assert_eq!(t.seen_max(7), Some(0.0));
            t.mark_seen(2, 0);
            assert_eq!(t.seen_entries(), vec![(2, 1), (7, (1 << 3) | (1 << 5))]);
            assert_eq!(t.seen_columns(7), 0b10_1000);
            let mut other = QTable::tracking_seen(keys, 8, 0.0);
            other.row_mut(7)[3] = -2.0;
            assert_ne!(t, other, "equal values, other seen entries");
        }
    }

    #[test]
    fn a_table_that_does_not_track_sees_nothing() {
        let mut t = QTable::new(10, 6, 0.0);
        t.mark_seen(3, 2);
        assert!(!t.tracks_seen());
        assert_eq!((t.seen_columns(3), t.seen_max(3)), (0, None));
        assert!(t.seen_entries().is_empty());
        assert_ne!(t, QTable::tracking_seen(10, 6, 0.0));
    }
}
