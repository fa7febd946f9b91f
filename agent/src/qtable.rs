//! The Q-table: one row of action values per key, dense where the keys can be indexed
//! within a memory budget, a hash map of the rows met so far where not.

use std::collections::HashMap;

/// The most entries (keys x columns) a dense table may have: 2^24 `f32`s, 64 MiB. Beyond
/// it the table keeps only the rows it has met, in a hash map.
pub const DENSE_LIMIT: u64 = 1 << 24;

/// Q-values, `columns` per key; rows never written read as `initial`.
///
/// Two tables are equal when they hold the same values for every key, however stored.
#[derive(Clone, Debug)]
pub struct QTable {
    key_count: u64,
    columns: usize,
    initial: f32,
    store: Store,
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
    }
}
