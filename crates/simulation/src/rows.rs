//! A run's rows on their way out: to a front end's [`Sink`] as they are made, so that a run
//! of ten million samples holds none of them, and through [`Totals`], the running figures
//! the summary gives of every row (the energy's and the constraints' drift), which a run
//! that keeps its rows folds the same way afterwards.

use super::Columns;

/// Where a front end takes a run's table as it is made: the recorded outputs at each time,
/// in time order (a CSV or JSON writer, an accumulator).
pub trait Sink {
    /// The outputs' names, once, before the first row (`t` is not among them).
    fn columns(&mut self, names: &[String]);
    /// The outputs recorded at `t`, in the order of their names, and the energy T + V there
    /// (for a front end that shows its drift row by row).
    fn row(&mut self, t: f64, outputs: &[f64], energy: f64);
}

/// What the summary says of every row, folded as the rows pass: the energy's drift from its
/// start and its scale, and the largest constraint residual. Each fold takes the rows in
/// time order from the same start value as a fold over the kept rows would, so the figures
/// have the same bits either way.
#[derive(Clone, Debug, Default)]
pub struct Totals {
    /// E at the first row.
    first_energy: Option<f64>,
    /// The time and E of the last row.
    last: Option<(f64, f64)>,
    /// What the jumps so far changed E by: an impact's loss, recorded as two rows at one time,
    /// before and after it.
    jumps: f64,
    /// The largest |E − E(0) − what the jumps changed|.
    energy_drift: f64,
    /// The largest of |E(0)|, |KE| and |PE|.
    energy_scale: f64,
    /// The largest residual of a kept constraint.
    constraint_drift: f64,
}

/// Where the figures of [`Totals`] sit in a row of observations.
#[derive(Clone, Debug)]
pub(super) struct Watched {
    /// How many of a row's first columns are outputs.
    pub outputs: usize,
    /// The columns of KE and PE.
    pub energies: (usize, usize),
    /// The constraints' residuals.
    pub constraints: Vec<usize>,
}

impl Watched {
    pub fn new(columns: &Columns, constraints: Vec<usize>) -> Watched {
        let energies = (columns.energies(), columns.energies() + 1);
        Watched { outputs: columns.outputs, energies, constraints }
    }

    /// T + V in a row of observations, as [`super::Outcome::energy`] gives it.
    pub fn energy(&self, row: &[f64]) -> f64 {
        row[self.energies.0] + row[self.energies.1]
    }
}

impl Totals {
    /// Takes one more row of observations, recorded at `t`, into the figures. A row at the
    /// time of the one before it is the state after a jump (an impact): what E changed by
    /// there is the jump's, not drift.
    pub(super) fn add(&mut self, watched: &Watched, t: f64, row: &[f64]) {
        let (k, p) = watched.energies;
        let e = watched.energy(row);
        let e0 = *self.first_energy.get_or_insert_with(|| {
            self.energy_scale = e.abs();
            e
        });
        if let Some((before, e_before)) = self.last {
            if before == t {
                self.jumps += e - e_before;
            }
        }
        self.last = Some((t, e));
        self.energy_scale = self.energy_scale.max(row[k].abs().max(row[p].abs()));
        self.energy_drift = self.energy_drift.max((e - e0 - self.jumps).abs());
        for &c in &watched.constraints {
            self.constraint_drift = self.constraint_drift.max(row[c]);
        }
    }

    /// The figures of rows kept, recorded at `times`: each taken in turn.
    pub(super) fn of(watched: &Watched, times: &[f64], rows: &[Vec<f64>]) -> Totals {
        let mut totals = Totals::default();
        for (t, row) in times.iter().zip(rows) {
            totals.add(watched, *t, row);
        }
        totals
    }

    /// What the run's jumps (impacts) changed the energy by, in all.
    pub fn energy_jumps(&self) -> f64 {
        self.jumps
    }

    /// The largest |E(t) − E(0)| less what the jumps up to t changed it by (none without
    /// contacts), and that relative to the energy scale.
    pub fn energy_drift(&self) -> (f64, f64) {
        let scale = self.energy_scale.max(f64::MIN_POSITIVE);
        (self.energy_drift, self.energy_drift / scale)
    }

    /// The largest residual of a kept constraint over the rows.
    pub fn constraint_drift(&self) -> f64 {
        self.constraint_drift
    }
}

/// The rows of a run handed to a front end's sink, the outputs alone, with the figures of
/// [`Totals`] taken on the way. The names go to the sink with the first row, or at the end of
/// a run that recorded none: a run refused before its start (a setting, the method) hands it
/// nothing.
pub(super) struct Tee<'a> {
    pub sink: &'a mut dyn Sink,
    /// The outputs' names, until they are handed on.
    pub names: Option<&'a [String]>,
    pub watched: &'a Watched,
    pub totals: Totals,
}

impl Tee<'_> {
    /// Hands the sink the names, unless it has them.
    pub fn begin(&mut self) {
        if let Some(names) = self.names.take() {
            self.sink.columns(names);
        }
    }
}

impl sim::Rows for Tee<'_> {
    fn row(&mut self, t: f64, row: &[f64]) {
        self.begin();
        self.totals.add(self.watched, t, row);
        let energy = self.watched.energy(row);
        self.sink.row(t, &row[..self.watched.outputs], energy);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The figures folded row by row are those of the folds over the kept rows that the
    /// summary made before the rows streamed, bit for bit (NaN, a residual's sign and no rows
    /// at all included).
    #[test]
    fn totals_fold_as_the_kept_rows_did() {
        let watched = Watched { outputs: 1, energies: (1, 2), constraints: vec![3, 4] };
        let cases: [&[[f64; 5]]; 4] = [
            &[],
            &[[0.0, 1.5, -9.0, 1e-9, 2e-12]],
            &[
                [0.0, 0.1, -3.0, 0.0, 0.0],
                [0.5, 0.7, -3.6000000000000005, 3e-10, -1e-9],
                [1.0, f64::NAN, -2.0, f64::NAN, 4e-10],
                [1.5, 1.3, -4.2, 2e-10, 1e-11],
            ],
            &[[0.0, 1e300, 1e300, 0.0, 0.0], [1.0, -1e300, 0.5, 0.0, 0.0]],
        ];
        for rows in cases {
            let rows: Vec<Vec<f64>> = rows.iter().map(|r| r.to_vec()).collect();
            let times: Vec<f64> = (0..rows.len()).map(|k| k as f64).collect();
            let totals = Totals::of(&watched, &times, &rows);
            // The summary's folds as they were written over the kept rows.
            let (k, p) = watched.energies;
            let e: Vec<f64> = rows.iter().map(|r| r[k] + r[p]).collect();
            let e0 = e.first().copied().unwrap_or(0.0);
            let scale = rows
                .iter()
                .map(|r| r[k].abs().max(r[p].abs()))
                .fold(e0.abs(), f64::max)
                .max(f64::MIN_POSITIVE);
            let drift = e.iter().map(|v| (v - e0).abs()).fold(0.0, f64::max);
            let constraint = rows
                .iter()
                .flat_map(|r| watched.constraints.iter().map(move |&c| r[c]))
                .fold(0.0, f64::max);
            let (got, relative) = totals.energy_drift();
            assert_eq!(got.to_bits(), drift.to_bits(), "{rows:?}");
            assert_eq!(relative.to_bits(), (drift / scale).to_bits(), "{rows:?}");
            assert_eq!(totals.constraint_drift().to_bits(), constraint.to_bits(), "{rows:?}");
        }
    }

    /// Two rows at one time are the state before and after a jump: what E changed by between
    /// them is the jump's, and E's drift is measured from E(0) less it.
    #[test]
    fn a_jump_is_not_drift() {
        let watched = Watched { outputs: 1, energies: (1, 2), constraints: vec![] };
        let times = [0.0, 0.5, 1.0, 1.0, 2.0];
        let rows: Vec<Vec<f64>> = [
            [0.0, 1.0, 2.0],
            [0.0, 1.5, 1.5],
            [0.0, 2.0, 1.0],
            [0.0, 0.5, 1.0],
            [0.0, 0.25, 1.0 + 1e-9],
        ]
        .iter()
        .map(|r| r.to_vec())
        .collect();
        let totals = Totals::of(&watched, &times, &rows);
        assert_eq!(totals.energy_jumps(), -1.5);
        let (drift, _) = totals.energy_drift();
        assert!((drift - 0.25).abs() < 1e-8, "{drift}");
    }
}
