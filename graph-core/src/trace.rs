//! Recorded signals in memory: what plots are drawn from and checks are
//! evaluated on.

/// Recorded signals in memory, column-major.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Trace {
    pub headers: Vec<String>,
    pub columns: Vec<Vec<f64>>,
}

impl Trace {
    pub fn new(headers: Vec<String>) -> Self {
        let columns = vec![Vec::new(); headers.len()];
        Trace { headers, columns }
    }

    pub fn push(&mut self, row: &[f64]) {
        for (c, v) in self.columns.iter_mut().zip(row) {
            c.push(*v);
        }
    }

    /// Time stamps.
    pub fn t(&self) -> &[f64] {
        &self.columns[0]
    }

    /// A column by header name.
    pub fn column(&self, name: &str) -> Option<&[f64]> {
        self.headers.iter().position(|h| h == name).map(|i| self.columns[i].as_slice())
    }

    /// Linear interpolation of column `name` at time `t`.
    pub fn at(&self, name: &str, t: f64) -> Option<f64> {
        let (ts, ys) = (self.t(), self.column(name)?);
        let i = ts.partition_point(|&x| x <= t);
        Some(match i {
            0 => ys[0],
            i if i >= ts.len() => ys[ts.len() - 1],
            i if ts[i] == ts[i - 1] => ys[i],
            i => ys[i - 1] + (ys[i] - ys[i - 1]) * (t - ts[i - 1]) / (ts[i] - ts[i - 1]),
        })
    }
}
