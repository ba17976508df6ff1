//! The exact parallel top-k scan.

use super::*;

impl Store {
    /// The chunks and their row counts, as committed now.
    pub(super) fn plan(&self) -> Result<Vec<(i64, usize)>, StoreError> {
        let mut stmt = self
            .conn
            .prepare("SELECT chunk, rows FROM chunks ORDER BY chunk")
            .map_err(self.sql())?;
        let rows = stmt
            .query_map([], |r| Ok((r.get::<_, i64>(0)?, r.get::<_, i64>(1)? as usize)))
            .map_err(self.sql())?;
        let plan = rows.collect::<Result<Vec<_>, _>>().map_err(self.sql())?;
        if let Some(&(chunk, rows)) = plan.iter().find(|p| p.1 > self.chunk_rows) {
            return Err(integrity::corrupt(
                &self.path,
                integrity::chunk_record(chunk, rows, self.chunk_rows),
                format!("holds {rows} rows of {} per chunk", self.chunk_rows),
            ));
        }
        Ok(plan)
    }

    /// The `k` stored shapes nearest to a query under `metric` (exact, parallel; see
    /// [`Store::search`]).
    ///
    /// # Errors
    /// [`StoreError::Dimension`] / [`StoreError::NonFinite`] for a bad query; as
    /// [`Store::search`].
    pub fn search_metric<M: Metric + ?Sized>(
        &self,
        query: &[f64],
        k: usize,
        metric: &M,
    ) -> Result<Vec<Hit>, StoreError> {
        if query.len() != self.dimension {
            return Err(StoreError::Dimension {
                name: "query".into(),
                expected: self.dimension,
                found: query.len(),
            });
        }
        if let Some(index) = query.iter().position(|x| !x.is_finite()) {
            return Err(StoreError::NonFinite {
                name: "query".into(),
                index,
                value: query[index],
            });
        }
        if !metric.checks_values() {
            return self.search(k, |row| metric.eval(query, row));
        }
        if let Some((index, reason)) = query
            .iter()
            .enumerate()
            .find_map(|(i, &x)| metric.refuse(x).map(|r| (i, r)))
        {
            return Err(StoreError::InvalidParameter {
                name: "query",
                reason: format!("value {} at index {index} {reason}", query[index]),
            });
        }
        self.search_checked(k, |row| {
            match row
                .iter()
                .enumerate()
                .find_map(|(i, &x)| metric.refuse(f64::from(x)).map(|r| (i, r)))
            {
                Some((i, reason)) => Err(format!("value {} at index {i} {reason}", row[i])),
                None => Ok(metric.eval(query, row)),
            }
        })
    }

    /// The `k` stored shapes with the smallest `distance(vector)`, nearest first, ties broken
    /// by id (so the answer does not depend on the thread count). An exact scan of every
    /// committed vector: each rayon worker opens a read-only connection and reads whole chunks;
    /// only shapes committed when the scan starts are considered.
    ///
    /// # Errors
    /// [`StoreError::NanDistance`] if `distance` returns NaN; [`StoreError::CorruptIndex`]
    /// naming a chunk whose checksum does not match or a shape with a non-finite value;
    /// [`StoreError::Sqlite`].
    pub fn search<F>(&self, k: usize, distance: F) -> Result<Vec<Hit>, StoreError>
    where
        F: Fn(&[f32]) -> f64 + Sync,
    {
        self.search_checked(k, |row| Ok(distance(row)))
    }

    /// [`Store::search`] with a distance that may refuse a stored row (`Err(reason)`: e.g. a
    /// negative bin where the distance needs histograms), which fails the search with
    /// [`StoreError::InvalidRow`] naming the shape.
    ///
    /// # Errors
    /// [`StoreError::InvalidRow`]; as [`Store::search`].
    pub fn search_checked<F>(&self, k: usize, distance: F) -> Result<Vec<Hit>, StoreError>
    where
        F: Fn(&[f32]) -> Result<f64, String> + Sync,
    {
        let plan = self.plan()?;
        // No more hits than stored rows: k = 2⁶² must not size a heap.
        let k = k.min(plan.iter().map(|p| p.1).sum());
        if k == 0 {
            return Ok(Vec::new());
        }
        let next = AtomicUsize::new(0);
        let workers = rayon::current_num_threads().clamp(1, plan.len().max(1));
        let dim = self.dimension;
        let chunk_rows = self.chunk_rows;
        let path = self.path.as_path();
        let layout = self.layout();
        let partial: Vec<Vec<(f64, u64)>> = (0..workers)
            .into_par_iter()
            .map(|_| -> Result<Vec<(f64, u64)>, StoreError> {
                let conn = connect(path, true)?;
                let mut best = TopK::new(k);
                loop {
                    let i = next.fetch_add(1, Ordering::Relaxed);
                    let Some(&(chunk, rows)) = plan.get(i) else { break };
                    let values = read_chunk(&conn, &layout, chunk, rows)?;
                    let first = chunk as u64 * chunk_rows as u64;
                    for (r, row) in values.chunks_exact(dim).enumerate() {
                        let id = first + r as u64;
                        let d = distance(row).map_err(|reason| StoreError::InvalidRow {
                            path: path.to_path_buf(),
                            id,
                            reason,
                        })?;
                        if d.is_nan() {
                            return Err(StoreError::NanDistance { id });
                        }
                        best.push(d, id);
                    }
                }
                Ok(best.into_sorted())
            })
            .collect::<Result<_, _>>()?;
        let mut all: Vec<(f64, u64)> = partial.into_iter().flatten().collect();
        all.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        all.truncate(k);
        all.into_iter()
            .map(|(distance, id)| {
                let row = self.shape(id)?.ok_or_else(|| {
                    integrity::corrupt(
                        &self.path,
                        format!("shape {id}"),
                        "a stored vector without its shape row",
                    )
                })?;
                Ok(Hit {
                    id,
                    name: row.name,
                    info: row.info,
                    distance,
                })
            })
            .collect()
    }
}

/// What reading a chunk needs to know of its store (shared by the scan's workers).
pub(super) struct Layout<'a> {
    pub(super) path: &'a Path,
    pub(super) dimension: usize,
    pub(super) chunk_rows: usize,
    pub(super) checksums: bool,
}

impl Store {
    pub(super) fn layout(&self) -> Layout<'_> {
        Layout {
            path: &self.path,
            dimension: self.dimension,
            chunk_rows: self.chunk_rows,
            checksums: self.checksums,
        }
    }
}

/// The first `rows` vectors of a chunk, decoded. The whole chunk is read in one statement (one
/// snapshot: an append may have extended it since the scan was planned) and verified against
/// its checksum, and every value must be finite: a damaged or tampered blob is refused naming
/// the chunk or the shape, never ranked.
pub(super) fn read_chunk(
    conn: &Connection,
    layout: &Layout<'_>,
    chunk: i64,
    rows: usize,
) -> Result<Vec<f32>, StoreError> {
    let Layout {
        path,
        dimension: dim,
        chunk_rows,
        checksums,
    } = *layout;
    let sql = |source| sqlite_error(path, source);
    let record = |n: usize| integrity::chunk_record(chunk, n, chunk_rows);
    if rows > chunk_rows {
        return Err(integrity::corrupt(
            path,
            record(rows),
            format!("holds {rows} rows of {chunk_rows} per chunk"),
        ));
    }
    let query = if checksums {
        "SELECT rows, checksum, data FROM chunks WHERE chunk = ?1"
    } else {
        "SELECT rows, NULL, data FROM chunks WHERE chunk = ?1"
    };
    let mut stmt = conn.prepare_cached(query).map_err(sql)?;
    let read = stmt
        .query_row([chunk], |r| {
            let stored_rows = r.get::<_, i64>(0)?.max(0) as usize;
            let stored: Option<i64> = r.get(1)?;
            let data = r.get_ref(2)?;
            let Ok(data) = data.as_blob() else {
                return Ok(Err(integrity::corrupt(
                    path,
                    record(stored_rows),
                    "its data is not a blob",
                )));
            };
            // invariant: rows ≤ chunk_rows and chunk_rows × dim × 4 ≤ MAX_CHUNK_BYTES (checked on open).
            let bytes = rows * dim * 4;
            if stored_rows < rows || stored_rows > chunk_rows || data.len() != stored_rows * dim * 4 {
                return Ok(Err(integrity::corrupt(
                    path,
                    record(stored_rows),
                    format!(
                        "has {} bytes for {stored_rows} rows of {dim} values, and {rows} rows are to be read",
                        data.len()
                    ),
                )));
            }
            if let Err(e) = integrity::verify(path, stored, integrity::chunk_sum(chunk, stored_rows, data), || {
                record(stored_rows)
            }) {
                return Ok(Err(e));
            }
            Ok(integrity::decode(path, chunk, chunk_rows, dim, &data[..bytes]))
        })
        .optional()
        .map_err(sql)?;
    read.unwrap_or_else(|| {
        Err(integrity::corrupt(
            path,
            record(rows),
            "is missing from the chunk table",
        ))
    })
}

/// The k smallest (distance, id) pairs seen, as a max-heap on (distance, id).
struct TopK {
    k: usize,
    heap: std::collections::BinaryHeap<Ranked>,
}

#[derive(PartialEq)]
struct Ranked(f64, u64);

impl Eq for Ranked {}

impl PartialOrd for Ranked {
    fn partial_cmp(&self, other: &Self) -> Option<std::cmp::Ordering> {
        Some(self.cmp(other))
    }
}

impl Ord for Ranked {
    fn cmp(&self, other: &Self) -> std::cmp::Ordering {
        self.0.total_cmp(&other.0).then(self.1.cmp(&other.1))
    }
}

impl TopK {
    fn new(k: usize) -> Self {
        Self {
            k,
            heap: std::collections::BinaryHeap::with_capacity(k + 1),
        }
    }

    #[inline]
    fn push(&mut self, distance: f64, id: u64) {
        let item = Ranked(distance, id);
        if self.heap.len() < self.k {
            self.heap.push(item);
        } else if let Some(top) = self.heap.peek() {
            if item < *top {
                self.heap.pop();
                self.heap.push(item);
            }
        }
    }

    fn into_sorted(self) -> Vec<(f64, u64)> {
        self.heap.into_sorted_vec().into_iter().map(|r| (r.0, r.1)).collect()
    }
}
