//! `lagrange inverse-dynamics`'s files: the trajectory read from CSV (a time column `t`, then
//! per coordinate its position, rate and acceleration as `x`, `x'` and `x''`, the columns
//! `lagrange simulate --output` writes), and the generalized forces written as CSV. The
//! forces themselves are `engine::inverse`'s.

use engine::inverse::InverseDynamics;

/// A trajectory's rows: time, then positions, rates and accelerations in coordinate order.
pub struct Trajectory {
    pub times: Vec<f64>,
    pub positions: Vec<Vec<f64>>,
    pub rates: Vec<Vec<f64>>,
    pub accelerations: Vec<Vec<f64>>,
}

/// Reads the CSV `text` of the file `path` for the given coordinates. Other columns are
/// ignored, so that a `simulate` table with more outputs serves. The error is ready to print,
/// naming the file, and for a bad cell its line, column and header.
pub fn read_trajectory(
    path: &str,
    text: &str,
    coordinates: &[String],
) -> Result<Trajectory, String> {
    let mut wanted = vec!["t".to_string()];
    for suffix in ["", "'", "''"] {
        wanted.extend(coordinates.iter().map(|c| format!("{c}{suffix}")));
    }
    let needs = format!(
        "`t` and, for each coordinate, its position, rate and acceleration ({})",
        wanted[1..].join(", ")
    );
    let hint = format!(
        "`lagrange simulate SCENE --output {} --out FILE.csv` writes one",
        wanted[1..].join(",")
    );
    let table = crate::trajectory::read_columns(
        path,
        text,
        &crate::trajectory::Wanted { columns: &wanted, needs: &needs, hint: &hint },
    )?;
    let n = coordinates.len();
    let mut trajectory = Trajectory {
        times: Vec::new(),
        positions: Vec::new(),
        rates: Vec::new(),
        accelerations: Vec::new(),
    };
    for values in table.rows {
        trajectory.times.push(values[0]);
        trajectory.positions.push(values[1..1 + n].to_vec());
        trajectory.rates.push(values[1 + n..1 + 2 * n].to_vec());
        trajectory.accelerations.push(values[1 + 2 * n..].to_vec());
    }
    Ok(trajectory)
}

/// The generalized forces along the trajectory as CSV: `t`, then `tau_x` per coordinate `x`,
/// numbers as Rust's shortest round-trip decimals.
pub fn torques_csv(
    inverse: &mut InverseDynamics,
    trajectory: &Trajectory,
) -> Result<String, engine::Error> {
    let n = inverse.coordinates().len();
    let mut out = csv::Writer::from_writer(Vec::new());
    let header = std::iter::once("t".to_string())
        .chain(inverse.coordinates().iter().map(|c| format!("tau_{c}")));
    out.write_record(header).expect("writing to memory");
    let mut tau = vec![0.0; n];
    for (k, t) in trajectory.times.iter().enumerate() {
        inverse.torques(
            *t,
            &trajectory.positions[k],
            &trajectory.rates[k],
            &trajectory.accelerations[k],
            &mut tau,
        )?;
        let numbers = std::iter::once(t).chain(&tau);
        out.write_record(numbers.map(|x| crate::simulate::number(*x))).expect("writing to memory");
    }
    let bytes = out.into_inner().expect("writing to memory");
    Ok(String::from_utf8(bytes).expect("UTF-8 in, UTF-8 out"))
}

/// What the forces mean with constraints kept with multipliers, for stderr; empty without.
pub fn note(inverse: &InverseDynamics) -> String {
    let kept = inverse.kept_constraints();
    if kept.is_empty() {
        return String::new();
    }
    let names: Vec<String> = kept.iter().map(|c| format!("`{c}`")).collect();
    let names = if names.len() == 1 {
        format!("the constraint {} is", names[0])
    } else {
        format!("the constraints {} are", names.join(", "))
    };
    format!(
        "note: {} kept with multipliers: these forces leave the constraints the load they \
         would carry without them (the least in τᵀ·M⁻¹·τ); adding Jᵀμ for any μ gives the \
         same motion\n",
        names
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn names() -> Vec<String> {
        vec!["x".to_string()]
    }

    #[test]
    fn a_simulate_table_with_extra_columns_is_read() {
        let text = "t,KE,x,x',x''\n0,1,0.5,2,-3\n0.1,1,0.7,1.9,-2.9\n";
        let t = read_trajectory("run.csv", text, &names()).unwrap();
        assert_eq!(t.times, [0.0, 0.1]);
        assert_eq!(t.positions, [[0.5], [0.7]]);
        assert_eq!(t.rates, [[2.0], [1.9]]);
        assert_eq!(t.accelerations, [[-3.0], [-2.9]]);
    }

    #[test]
    fn a_bad_cell_is_named_by_file_line_and_column() {
        let text = "t,x,x',x''\n0,0.5,2,-3\n0.1,0.7,oops,-2.9\n";
        let e = read_trajectory("run.csv", text, &names()).err().unwrap();
        assert_eq!(e, "error: run.csv:3:3: `oops` in the column `x'` is not a finite number");
    }

    #[test]
    fn a_missing_column_says_what_a_trajectory_needs() {
        let e = read_trajectory("run.csv", "t,x,x'\n0,1,2\n", &names()).err().unwrap();
        assert!(e.starts_with("error: run.csv has no column `x''`: a trajectory needs"), "{e}");
        assert!(e.contains("--output x,x',x''"), "{e}");
        let e = read_trajectory("run.csv", "t,x,x',x''\n", &names()).err().unwrap();
        assert_eq!(e, "error: run.csv has a header but no rows");
    }
}
