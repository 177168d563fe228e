//! Recorded rows kept column by column, a batch at a time: how an
//! accelerated run's library records and hands its rows to the program.
//! Each column of a batch is then one copy into the trace, where rows laid
//! one after another were a gather per value (40 instructions a LADRC row).

use std::collections::TryReserveError;

/// Up to `capacity` rows of `width` values, row r's value c at
/// `c·capacity + r`: the columns one after another, each `capacity` long.
#[derive(Clone, Debug, Default)]
pub struct ColumnBatch {
    values: Vec<f64>,
    width: usize,
    capacity: usize,
    rows: usize,
}

impl ColumnBatch {
    /// An empty batch for rows of `width` values, `capacity` of them;
    /// allocated here, once.
    pub fn new(width: usize, capacity: usize) -> Result<Self, TryReserveError> {
        let capacity = capacity.max(1);
        let mut values = Vec::new();
        values.try_reserve_exact(width.saturating_mul(capacity))?;
        values.resize(width * capacity, 0.0);
        Ok(ColumnBatch { values, width, capacity, rows: 0 })
    }

    pub fn width(&self) -> usize {
        self.width
    }

    /// How many rows it holds when full.
    pub fn capacity(&self) -> usize {
        self.capacity
    }

    pub fn is_full(&self) -> bool {
        self.rows >= self.capacity
    }

    pub fn is_empty(&self) -> bool {
        self.rows == 0
    }

    pub fn clear(&mut self) {
        self.rows = 0;
    }

    /// Appends a row of the batch's width (a generated step's recorded
    /// row, whose width is a constant); a full batch, or a row of another
    /// width, takes [`ColumnBatch::push_slice`]'s checked way.
    #[inline(always)]
    pub fn push<const W: usize>(&mut self, row: [f64; W]) {
        let r = self.rows;
        if W != self.width || r >= self.capacity {
            return self.push_slice(&row);
        }
        for (c, v) in row.into_iter().enumerate() {
            // SAFETY: `values` holds `width·capacity` values (`new`, and
            // nothing resizes it), c < W = width and r < capacity, so
            // c·capacity + r < width·capacity. Unchecked: a check per
            // value, or the division `chunks_exact` makes, was a third of
            // what a recorded row cost.
            unsafe { *self.values.get_unchecked_mut(c * self.capacity + r) = v };
        }
        self.rows = r + 1;
    }

    /// Appends `row`: its first `width` values, zeros for those it lacks;
    /// nothing when the batch is full.
    #[cold]
    #[inline(never)]
    pub fn push_slice(&mut self, row: &[f64]) {
        let r = self.rows;
        if r >= self.capacity {
            return;
        }
        for (c, column) in self.values.chunks_exact_mut(self.capacity).enumerate() {
            column[r] = row.get(c).copied().unwrap_or(0.0);
        }
        self.rows = r + 1;
    }

    /// The rows held, as the parts [`Columns::from_parts`] reads them:
    /// values, width, stride, rows (what crosses the library's interface).
    pub fn parts(&self) -> (&[f64], usize, usize, usize) {
        (&self.values, self.width, self.capacity, self.rows)
    }
}

/// A batch's rows as a reader sees them: `rows` rows of `width` values,
/// column c's at `c·stride` onwards.
#[derive(Clone, Copy, Debug)]
pub struct Columns<'a> {
    values: &'a [f64],
    width: usize,
    stride: usize,
    rows: usize,
}

impl<'a> Columns<'a> {
    /// The view of `values` laid out as [`ColumnBatch`] lays them; `None`
    /// unless every column's rows are inside `values`.
    pub fn from_parts(values: &'a [f64], width: usize, stride: usize, rows: usize) -> Option<Self> {
        let fits = rows <= stride && width.checked_mul(stride).is_some_and(|n| n <= values.len());
        fits.then_some(Columns { values, width, stride, rows })
    }

    pub fn rows(&self) -> usize {
        self.rows
    }

    pub fn width(&self) -> usize {
        self.width
    }

    /// Column `c`'s values, one per row.
    pub fn column(&self, c: usize) -> &'a [f64] {
        &self.values[c * self.stride..c * self.stride + self.rows]
    }

    /// Row `r` into `row` (its first `width` values).
    pub fn row_into(&self, r: usize, row: &mut [f64]) {
        for (c, v) in row.iter_mut().enumerate().take(self.width) {
            *v = self.values[c * self.stride + r];
        }
    }

    /// The last row's first value (a run's time), if there is a row with
    /// values.
    pub fn last_time(&self) -> Option<f64> {
        self.rows.checked_sub(1).and_then(|r| self.values.get(r).copied())
    }
}

#[cfg(test)]
mod tests {
    use super::{ColumnBatch, Columns};

    /// Rows pushed whole and as slices read back by column and by row
    /// through the parts that cross the library's interface; a full batch
    /// takes no more; parts that do not fit make no view.
    #[test]
    fn rows_go_in_by_row_and_come_out_by_column() {
        let mut batch = ColumnBatch::new(3, 4).expect("allocates");
        assert!(batch.is_empty());
        batch.push([0.0, 1.0, 2.0]);
        batch.push([0.5, 3.0, 4.0]);
        batch.push_slice(&[1.0, 5.0]);
        batch.push([1.5, 7.0, 8.0, 9.0]);
        assert!(batch.is_full());
        batch.push([2.0, 0.0, 0.0]);
        let (values, width, stride, rows) = batch.parts();
        let view = Columns::from_parts(values, width, stride, rows).expect("fits");
        assert_eq!((view.rows(), view.width()), (4, 3));
        assert_eq!(view.column(0), [0.0, 0.5, 1.0, 1.5]);
        assert_eq!(view.column(1), [1.0, 3.0, 5.0, 7.0]);
        assert_eq!(view.column(2), [2.0, 4.0, 0.0, 8.0]);
        let mut row = [0.0; 3];
        view.row_into(1, &mut row);
        assert_eq!(row, [0.5, 3.0, 4.0]);
        assert_eq!(view.last_time(), Some(1.5));
        assert!(Columns::from_parts(values, width, stride + 1, rows).is_none());
        assert!(Columns::from_parts(values, width, stride, stride + 1).is_none());
        batch.clear();
        let (values, width, stride, rows) = batch.parts();
        assert!(
            batch.is_empty() && Columns::from_parts(values, width, stride, rows).expect("fits").last_time().is_none()
        );
        // Rows without values (no time column) have no last time.
        let empty = Columns::from_parts(&[], 0, 4, 2).expect("fits");
        assert_eq!((empty.rows(), empty.last_time()), (2, None));
    }
}
