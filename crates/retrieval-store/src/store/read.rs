//! Reading metadata, shapes and vectors.

use super::*;

impl Store {
    /// The metadata value of `key`, if any, verified against its checksum.
    ///
    /// # Errors
    /// [`StoreError::CorruptIndex`] naming the entry; [`StoreError::Sqlite`].
    pub fn meta(&self, key: &str) -> Result<Option<Vec<u8>>, StoreError> {
        let query = if self.checksums {
            "SELECT value, checksum FROM meta WHERE key = ?1"
        } else {
            "SELECT value, NULL FROM meta WHERE key = ?1"
        };
        let Some((value, stored)) = self
            .conn
            .query_row(query, [key], |r| {
                Ok((r.get::<_, Vec<u8>>(0)?, r.get::<_, Option<i64>>(1)?))
            })
            .optional()
            .map_err(self.sql())?
        else {
            return Ok(None);
        };
        integrity::verify(&self.path, stored, integrity::meta_sum(key, &value), || {
            integrity::meta_record(key)
        })?;
        Ok(Some(value))
    }

    /// `SELECT` of the shape columns, then `rest` (the checksum read as NULL in a version 1
    /// file).
    fn shape_query(&self, rest: &str) -> String {
        let checksum = if self.checksums { "checksum" } else { "NULL" };
        format!("SELECT id, name, info, {checksum} FROM shapes {rest}")
    }

    /// A shape row read by [`Self::shape_query`], verified against its checksum.
    fn shape_row(&self, row: (i64, String, String, Option<i64>)) -> Result<ShapeRow, StoreError> {
        let (id, name, info, stored) = row;
        let id = id as u64;
        integrity::verify(&self.path, stored, integrity::shape_sum(id, &name, &info), || {
            integrity::shape_record(id, &name)
        })?;
        Ok(ShapeRow { id, name, info })
    }

    fn one_shape(&self, rest: &str, arg: rusqlite::types::Value) -> Result<Option<ShapeRow>, StoreError> {
        self.conn
            .query_row(&self.shape_query(rest), [arg], |r| {
                Ok((r.get(0)?, r.get(1)?, r.get(2)?, r.get(3)?))
            })
            .optional()
            .map_err(self.sql())?
            .map(|row| self.shape_row(row))
            .transpose()
    }

    /// The shape of `id`, if any, verified against its checksum.
    ///
    /// # Errors
    /// [`StoreError::CorruptIndex`] naming the shape; [`StoreError::Sqlite`].
    pub fn shape(&self, id: u64) -> Result<Option<ShapeRow>, StoreError> {
        self.one_shape("WHERE id = ?1", rusqlite::types::Value::Integer(id as i64))
    }

    /// The shape named `name`, if any, verified against its checksum.
    ///
    /// # Errors
    /// [`StoreError::CorruptIndex`] naming the shape; [`StoreError::Sqlite`].
    pub fn find(&self, name: &str) -> Result<Option<ShapeRow>, StoreError> {
        self.one_shape("WHERE name = ?1", rusqlite::types::Value::Text(name.into()))
    }

    /// Every shape, by increasing id, each verified against its checksum.
    ///
    /// # Errors
    /// [`StoreError::CorruptIndex`] naming the first damaged shape; [`StoreError::Sqlite`].
    pub fn shapes(&self) -> Result<Vec<ShapeRow>, StoreError> {
        let mut stmt = self
            .conn
            .prepare(&self.shape_query("ORDER BY id"))
            .map_err(self.sql())?;
        let rows = stmt
            .query_map([], |r| Ok((r.get(0)?, r.get(1)?, r.get(2)?, r.get(3)?)))
            .map_err(self.sql())?;
        let mut out = Vec::new();
        for row in rows {
            out.push(self.shape_row(row.map_err(self.sql())?)?);
        }
        Ok(out)
    }

    /// The vector of shape `id` (as stored, f32), if any.
    ///
    /// # Errors
    /// [`StoreError::CorruptIndex`] naming the chunk (checksum) or the shape (a non-finite
    /// value); [`StoreError::Sqlite`].
    pub fn vector(&self, id: u64) -> Result<Option<Vec<f32>>, StoreError> {
        let n = self.len()? as u64;
        if id >= n {
            return Ok(None);
        }
        let chunk = (id as usize / self.chunk_rows) as i64;
        let offset = id as usize % self.chunk_rows;
        let values = read_chunk(&self.conn, &self.layout(), chunk, offset + 1)?;
        Ok(Some(values[offset * self.dimension..].to_vec()))
    }

    /// Every vector, row-major (`len() × dimension()`), by increasing id.
    ///
    /// # Errors
    /// [`StoreError::CorruptIndex`] naming the chunk (checksum) or the shape (a non-finite
    /// value); [`StoreError::Sqlite`].
    pub fn vectors(&self) -> Result<Vec<f32>, StoreError> {
        let plan = self.plan()?;
        let total = plan.iter().map(|p| p.1).sum::<usize>().saturating_mul(self.dimension);
        let mut out = Vec::new();
        out.try_reserve_exact(total).map_err(|_| StoreError::TooLarge {
            path: self.path.clone(),
            what: format!("{total} stored values"),
        })?;
        for (chunk, rows) in plan {
            out.extend(read_chunk(&self.conn, &self.layout(), chunk, rows)?);
        }
        Ok(out)
    }
}
