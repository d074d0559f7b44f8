//! The exported functions of the C source: each gathers the slots from its arguments, runs
//! the programs, and solves the augmented system [M −Jᵀ; J 0] where it needs the
//! accelerations, as the Rust module does.

use std::fmt::Write;

use crate::source::c::literal;

use super::of_state;
use crate::codegen::{stabilised_gamma, stabilised_partials, Equations};

/// Every exported function, with the static ones they share.
pub(super) fn all(e: &Equations, name: &str) -> String {
    let mut s = augmented(e);
    s.push_str(&solved(e));
    s.push_str(&initial_state(e, name));
    for (function, program, out) in [
        ("mass_matrix", "mass_matrix", "M"),
        ("forcing", "forcing", "f"),
        ("constraints", "constraints", "rows"),
        ("outputs", "outputs", "out"),
        ("energies", "energies", "ke_pe"),
    ] {
        s.push_str(&evaluation(e, name, function, program, out));
    }
    s.push_str(&rhs(e, name));
    s.push_str(&jacobian(e, name));
    s.push_str(&reactions(e, name));
    s.push_str(&inverse_dynamics(e, name));
    if e.sizes.contacts > 0 {
        s.push_str(&gaps(e, name));
        s.push_str(&impact(e, name));
    }
    s
}

/// `static void augmented(input, a, b)`: [M −Jᵀ; J 0] (row-major) and (f, γ), γ stabilised
/// as `sim::Mechanical` stabilises it (Baumgarte, at `sim::BAUMGARTE_RATE`), with its bits:
/// an importer's solver then holds the constraints as `simulate` does rather than let them
/// drift.
fn augmented(e: &Equations) -> String {
    let (n, m) = (e.sizes.coordinates, e.sizes.constraints);
    let size = n + m;
    let mut s = String::from(
        "/* [M -J^T; J 0] (row-major) and (f, gamma) at the slots input, gamma Baumgarte-\n \
         * stabilised as lagrange simulate holds kept constraints. */\n\
         static void augmented(const double *input, double *a, double *b)\n{\n",
    );
    let _ = writeln!(s, "    double mass[{}];\n    double f[{n}];\n    int i, j;", n * n);
    if m > 0 {
        let _ = writeln!(s, "    double rows[{}];\n    int c;", m * (n + 3));
    }
    s.push_str("    eval_mass_matrix(input, mass);\n    eval_forcing(input, f);\n");
    let _ = writeln!(
        s,
        "    for (i = 0; i < {n}; i++) {{\n        for (j = 0; j < {n}; j++) {{\n            \
         a[i * {size} + j] = mass[j * {n} + i];\n        }}\n        b[i] = f[i];\n    }}"
    );
    if m > 0 {
        let width = n + 3;
        let _ = writeln!(
            s,
            "    eval_constraints(input, rows);\n    for (c = 0; c < {m}; c++) {{\n        \
             for (j = 0; j < {n}; j++) {{\n            a[({n} + c) * {size} + j] = rows[c * {width} + j];\n            \
             a[j * {size} + {n} + c] = -rows[c * {width} + j];\n        }}\n        \
             for (j = 0; j < {m}; j++) {{\n            a[({n} + c) * {size} + {n} + j] = 0.0;\n        }}\n        \
             b[{n} + c] = rows[c * {width} + {n}];\n    }}"
        );
        for (c, gamma) in stabilised_gamma(e, &literal).iter().enumerate() {
            let _ = writeln!(s, "    b[{}] = {gamma};", n + c);
        }
        // The contacts' rows held open, as a run holds an open contact: lambda = 0.
        for slot in e.contact_slots() {
            let _ = writeln!(
                s,
                "    for (j = 0; j < {n}; j++) {{\n        a[{} + j] = 0.0;\n        a[j * {size} + {}] = 0.0;\n    }}\n    a[{}] = 1.0;\n    b[{}] = 0.0;",
                (n + slot) * size,
                n + slot,
                (n + slot) * size + n + slot,
                n + slot
            );
        }
    }
    s.push_str("}\n\n");
    s
}

/// `static int solved(input, matrix, held)`: the augmented system at `input` (kept in
/// `matrix`) solved for (q̈, λ), and the slots of the partials and the reactions with them.
fn solved(e: &Equations) -> String {
    let (n, m) = (e.sizes.coordinates, e.sizes.constraints);
    let size = n + m;
    let constants = e.sizes.parameters + e.sizes.inputs;
    let mut s = String::from(
        "/*\n * [t, q, qdot, qddot, lambda, parameters, inputs] at the slots input, with qddot and\n \
         * lambda solved from the augmented system, which is left in matrix. Returns 1 when it\n \
         * is singular.\n */\n\
         static int solved(const double *input, double *matrix, double *held)\n{\n",
    );
    let _ = writeln!(s, "    double a[{}];\n    double b[{size}];\n    int i;", size * size);
    s.push_str("    augmented(input, a, b);\n");
    let _ = writeln!(
        s,
        "    for (i = 0; i < {}; i++) {{\n        matrix[i] = a[i];\n    }}",
        size * size
    );
    let _ = writeln!(s, "    if (solve_in_place({size}, a, b)) {{\n        return 1;\n    }}");
    let _ = writeln!(
        s,
        "    for (i = 0; i < {}; i++) {{\n        held[i] = input[i];\n    }}",
        1 + 2 * n
    );
    let _ = writeln!(
        s,
        "    for (i = 0; i < {size}; i++) {{\n        held[{} + i] = b[i];\n    }}",
        1 + 2 * n
    );
    if constants > 0 {
        let _ = writeln!(
            s,
            "    for (i = 0; i < {constants}; i++) {{\n        held[{} + i] = input[{} + i];\n    }}",
            1 + 3 * n + m,
            1 + 2 * n
        );
    }
    s.push_str("    return 0;\n}\n\n");
    s
}

fn initial_state(e: &Equations, name: &str) -> String {
    let k = e.sizes.parameters;
    let mut s = format!("void {name}_initial_state(const {name}_parameters *p, double *y)\n{{\n");
    let _ = writeln!(s, "    double input[{}];\n    int i;", 1 + k + e.sizes.inputs);
    // The start does not depend on the inputs, but its program has their slots.
    let _ = writeln!(
        s,
        "    double none[{n}];\n    double slots[{d}];\n    for (i = 0; i < {n}; i++) {{\n        none[i] = 0.0;\n    }}\n    \
         gather(0.0, none, none, p, {name}_default_inputs, slots);",
        n = e.sizes.coordinates,
        d = e.sizes.dynamics_inputs()
    );
    let _ = writeln!(s, "    input[0] = 0.0;");
    if k + e.sizes.inputs > 0 {
        let _ = writeln!(
            s,
            "    for (i = 0; i < {}; i++) {{\n        input[1 + i] = slots[{} + i];\n    }}",
            k + e.sizes.inputs,
            1 + 2 * e.sizes.coordinates
        );
    }
    s.push_str("    eval_start(input, y);\n}\n\n");
    s
}

/// A function of the state that runs one program on the gathered slots, or does nothing
/// where the scene has no such program (no kept constraint, no output).
fn evaluation(e: &Equations, name: &str, function: &str, program: &str, out: &str) -> String {
    let n = e.sizes.coordinates;
    let mut s = format!("{}\n{{\n", of_state(name, function, out));
    if e.program(program).is_some() {
        let _ = writeln!(s, "    double input[{}];", e.sizes.dynamics_inputs());
        let _ = writeln!(s, "    gather(t, y, y + {n}, p, u, input);");
        let _ = writeln!(s, "    eval_{program}(input, {out});");
    } else {
        let _ =
            writeln!(s, "    (void)t;\n    (void)y;\n    (void)p;\n    (void)u;\n    (void){out};");
    }
    s.push_str("    return 0;\n}\n\n");
    s
}

fn rhs(e: &Equations, name: &str) -> String {
    let (n, m) = (e.sizes.coordinates, e.sizes.constraints);
    let size = n + m;
    let mut s = format!("{}\n{{\n", of_state(name, "rhs", "dy"));
    let _ = writeln!(
        s,
        "    double input[{}];\n    double a[{}];\n    double b[{size}];\n    int i;",
        e.sizes.dynamics_inputs(),
        size * size
    );
    let _ = writeln!(s, "    gather(t, y, y + {n}, p, u, input);");
    if e.program("accelerations").is_some() {
        let _ = writeln!(
            s,
            "    eval_accelerations(input, b);\n    for (i = 0; i < {n} && isfinite(b[i]); i++) {{\n    }}\n    \
             if (i == {n}) {{\n        for (i = 0; i < {n}; i++) {{\n            dy[i] = y[{n} + i];\n            \
             dy[{n} + i] = b[i];\n        }}\n        return 0;\n    }}\n    \
             /* No number from the sweep: M's solve says whether M is singular. */"
        );
    }
    let _ = writeln!(s, "    augmented(input, a, b);");
    let _ = writeln!(s, "    if (solve_in_place({size}, a, b)) {{\n        return 1;\n    }}");
    let _ = writeln!(
        s,
        "    for (i = 0; i < {n}; i++) {{\n        dy[i] = y[{n} + i];\n        dy[{n} + i] = b[i];\n    }}"
    );
    s.push_str("    return 0;\n}\n\n");
    s
}

/// ∂(q̇, q̈)/∂(q, q̇): differentiating r = 0 and c = 0 along the state with q̈ and λ free
/// gives [M −Jᵀ; J 0]·∂(q̈, λ) = −∂(r, c), one solve per state component; c is the
/// stabilised row `augmented` solves, so its partials take those of Φ and Φ̇ with it.
fn jacobian(e: &Equations, name: &str) -> String {
    let (n, m) = (e.sizes.coordinates, e.sizes.constraints);
    let (size, width) = (n + m, 2 * n);
    let mut s = format!("{}\n{{\n", of_state(name, "jacobian", "jac"));
    let _ = writeln!(
        s,
        "    double input[{}];\n    double matrix[{}];\n    double a[{}];\n    double held[{}];\n    \
         double d[{}];\n    double x[{size}];\n    int i, col;",
        e.sizes.dynamics_inputs(),
        size * size,
        size * size,
        e.sizes.dynamics_inputs() + size,
        (n + 3 * m) * width
    );
    let _ = writeln!(s, "    gather(t, y, y + {n}, p, u, input);");
    s.push_str("    if (solved(input, matrix, held)) {\n        return 1;\n    }\n");
    s.push_str("    eval_partials(held, d);\n");
    // The rows' partials, stabilised as `augmented` stabilises γ.
    if m > 0 {
        let _ = writeln!(s, "    for (col = 0; col < {width}; col++) {{");
        for line in stabilised_partials(e, &literal) {
            let _ = writeln!(s, "        {line}");
        }
        // An open contact's row, lambda = 0, has no partials.
        for slot in e.contact_slots() {
            let _ = writeln!(s, "        d[{} + col] = 0.0;", (n + slot) * width);
        }
        s.push_str("    }\n");
    }
    let _ = writeln!(
        s,
        "    for (i = 0; i < {}; i++) {{\n        jac[i] = 0.0;\n    }}",
        width * width
    );
    let _ = writeln!(
        s,
        "    for (i = 0; i < {n}; i++) {{\n        jac[i * {width} + {n} + i] = 1.0;\n    }}"
    );
    let _ = writeln!(
        s,
        "    for (col = 0; col < {width}; col++) {{\n        \
         for (i = 0; i < {}; i++) {{\n            a[i] = matrix[i];\n        }}\n        \
         for (i = 0; i < {size}; i++) {{\n            x[i] = -d[i * {width} + col];\n        }}\n        \
         if (solve_in_place({size}, a, x)) {{\n            return 1;\n        }}\n        \
         for (i = 0; i < {n}; i++) {{\n            jac[({n} + i) * {width} + col] = x[i];\n        }}\n    }}",
        size * size
    );
    s.push_str("    return 0;\n}\n\n");
    s
}

fn reactions(e: &Equations, name: &str) -> String {
    let (n, m) = (e.sizes.coordinates, e.sizes.constraints);
    let size = n + m;
    let mut s = format!("{}\n{{\n", of_state(name, "reactions", "out"));
    if e.reactions.is_empty() {
        s.push_str("    (void)t;\n    (void)y;\n    (void)p;\n    (void)u;\n    (void)out;\n");
    } else {
        let _ = writeln!(
            s,
            "    double input[{}];\n    double matrix[{}];\n    double held[{}];",
            e.sizes.dynamics_inputs(),
            size * size,
            e.sizes.dynamics_inputs() + size
        );
        let _ = writeln!(s, "    gather(t, y, y + {n}, p, u, input);");
        s.push_str("    if (solved(input, matrix, held)) {\n        return 1;\n    }\n");
        s.push_str("    eval_reactions(held, out);\n");
    }
    s.push_str("    return 0;\n}\n\n");
    s
}

/// τ = M·q̈ − f, and with kept constraints τ + Jᵀμ with [M −Jᵀ; J 0]·(x, μ) = (τ, 0), the
/// one least in τᵀ·M⁻¹·τ, as `engine::inverse` gives it.
fn inverse_dynamics(e: &Equations, name: &str) -> String {
    let (n, m) = (e.sizes.coordinates, e.sizes.constraints);
    let size = n + m;
    let mut s = format!(
        "int {name}_inverse_dynamics(double t, const double *q, const double *qd, \
         const double *qdd, const {name}_parameters *p, const double *u, double *tau)\n{{\n"
    );
    let _ = writeln!(
        s,
        "    double input[{}];\n    double a[{}];\n    double b[{size}];\n    int i, j;",
        e.sizes.dynamics_inputs(),
        size * size
    );
    if m > 0 {
        let _ = writeln!(s, "    double matrix[{}];\n    int c;", size * size);
    }
    s.push_str("    gather(t, q, qd, p, u, input);\n    augmented(input, a, b);\n");
    let _ = writeln!(
        s,
        "    for (i = 0; i < {n}; i++) {{\n        double inertial = 0.0;\n        \
         for (j = 0; j < {n}; j++) {{\n            inertial += a[i * {size} + j] * qdd[j];\n        }}\n        \
         tau[i] = inertial - b[i];\n    }}"
    );
    if m > 0 {
        let _ = writeln!(
            s,
            "    for (i = 0; i < {}; i++) {{\n        matrix[i] = a[i];\n    }}\n    \
             for (i = 0; i < {size}; i++) {{\n        b[i] = i < {n} ? tau[i] : 0.0;\n    }}\n    \
             if (solve_in_place({size}, a, b)) {{\n        return 1;\n    }}\n    \
             for (c = 0; c < {m}; c++) {{\n        for (j = 0; j < {n}; j++) {{\n            \
             tau[j] += matrix[({n} + c) * {size} + j] * b[{n} + c];\n        }}\n    }}",
            size * size
        );
    }
    s.push_str("    return 0;\n}\n");
    s
}

/// `NAME_gaps`: per contact, its gap and normal rate, read from the constraints' rows.
fn gaps(e: &Equations, name: &str) -> String {
    let (n, m) = (e.sizes.coordinates, e.sizes.constraints);
    let width = n + 3;
    let mut s = format!(
        "void {name}_gaps(double t, const double *q, const double *qd, \
         const {name}_parameters *p, const double *u, double *out)\n{{\n"
    );
    let _ = writeln!(
        s,
        "    double input[{}];\n    double rows[{}];",
        e.sizes.dynamics_inputs(),
        m * width
    );
    s.push_str("    gather(t, q, qd, p, u, input);\n    eval_constraints(input, rows);\n");
    for (k, c) in e.prepared.contacts.iter().enumerate() {
        let _ = writeln!(s, "    out[{}] = rows[{}];", 2 * k, c.normal * width + n + 1);
        let _ = writeln!(s, "    out[{}] = rows[{}];", 2 * k + 1, e.row_rate(c.normal));
    }
    s.push_str("}\n\n");
    s
}

/// `NAME_impact`: the touching contacts' complementarity problem (see
/// [`crate::codegen::impact`]), built as a run builds it and solved by the source's
/// `complementarity`.
fn impact(e: &Equations, name: &str) -> String {
    let (n, m, count) = (e.sizes.coordinates, e.sizes.constraints, e.sizes.contacts);
    let (size, width) = (n + m, n + 3);
    let rows_max = e.contact_slots().len();
    let mut s = format!(
        "int {name}_impact(double t, const double *q, const double *qd_minus, \
         const {name}_parameters *p, const double *u, const int *touching, double *qd_plus, \
         double *impulses)\n{{\n"
    );
    let _ = writeln!(
        s,
        "    double input[{}];\n    double system[{}];\n    double a[{}];\n    double b[{size}];\n    \
         double rows[{}];\n    double e[{count}];\n    int slot[{rows_max}] = {{0}};\n    int normal_of[{rows_max}] = {{0}};\n    \
         double c[{rows_max}] = {{0.0}};\n    double x[{rows_max}] = {{0.0}};\n    double response[{}] = {{0.0}};\n    double delassus[{}] = {{0.0}};\n    \
         int r = 0, i, j, l, status;",
        e.sizes.dynamics_inputs(),
        size * size,
        size * size,
        m * width,
        n * rows_max,
        rows_max * rows_max
    );
    s.push_str("    gather(t, q, qd_minus, p, u, input);\n    augmented(input, system, b);\n");
    let _ = writeln!(
        s,
        "    eval_constraints(input, rows);\n    eval_restitutions(input + {}, e);",
        1 + 2 * n
    );
    s.push_str(
        "    /* The touching contacts' rows, each normal then its grip: slot, normal row, c. */\n",
    );
    for (k, contact) in e.prepared.contacts.iter().enumerate() {
        let _ = writeln!(s, "    if (touching[{k}]) {{");
        let _ = writeln!(
            s,
            "        slot[r] = {};\n        normal_of[r] = r;\n        c[r] = (1.0 + e[{k}]) * rows[{}];\n        r++;",
            contact.normal,
            e.row_rate(contact.normal)
        );
        if let Some(grip) = contact.grip {
            let _ = writeln!(
                s,
                "        slot[r] = {grip};\n        normal_of[r] = r - 1;\n        c[r] = rows[{}];\n        r++;",
                e.row_rate(grip)
            );
        }
        s.push_str("    }\n");
    }
    let _ = writeln!(
        s,
        "    /* S W^T, a column per row: the augmented system of the two-sided rows solved for it. */\n    \
         for (l = 0; l < r; l++) {{\n        for (i = 0; i < {}; i++) {{\n            a[i] = system[i];\n        }}\n        \
         for (i = 0; i < {size}; i++) {{\n            b[i] = i < {n} ? rows[slot[l] * {width} + i] : 0.0;\n        }}\n        \
         if (solve_in_place({size}, a, b)) {{\n            return 1;\n        }}\n        \
         for (i = 0; i < {n}; i++) {{\n            response[i * {rows_max} + l] = b[i];\n        }}\n    }}",
        size * size
    );
    let _ = writeln!(
        s,
        "    /* The Delassus operator A = W S W^T, symmetrised. */\n    for (i = 0; i < r; i++) {{\n        \
         for (j = 0; j < r; j++) {{\n            double v = 0.0;\n            for (l = 0; l < {n}; l++) {{\n                \
         v += rows[slot[i] * {width} + l] * response[l * {rows_max} + j];\n            }}\n            delassus[i * r + j] = v;\n        }}\n    }}\n    \
         for (i = 0; i < r; i++) {{\n        for (j = i + 1; j < r; j++) {{\n            \
         double v = (delassus[i * r + j] + delassus[j * r + i]) * 0.5;\n            delassus[i * r + j] = v;\n            delassus[j * r + i] = v;\n        }}\n    }}"
    );
    s.push_str("    status = complementarity(r, delassus, c, normal_of, x);\n    if (status) {\n        return status;\n    }\n");
    let _ = writeln!(
        s,
        "    /* The two-sided rows' impulses: the augmented system solved for W^T L. */\n    \
         for (i = 0; i < {}; i++) {{\n        a[i] = system[i];\n    }}\n    \
         for (i = 0; i < {size}; i++) {{\n        b[i] = 0.0;\n    }}\n    \
         for (l = 0; l < r; l++) {{\n        for (j = 0; j < {n}; j++) {{\n            b[j] += rows[slot[l] * {width} + j] * x[l];\n        }}\n    }}\n    \
         if (solve_in_place({size}, a, b)) {{\n        return 1;\n    }}\n    \
         for (i = 0; i < {n}; i++) {{\n        double v = 0.0;\n        for (l = 0; l < r; l++) {{\n            v += response[i * {rows_max} + l] * x[l];\n        }}\n        \
         qd_plus[i] = qd_minus[i] + v;\n    }}\n    \
         for (i = 0; i < {m}; i++) {{\n        impulses[i] = b[{n} + i];\n    }}\n    \
         for (l = 0; l < r; l++) {{\n        impulses[slot[l]] = x[l];\n    }}\n    return 0;\n}}\n",
        size * size
    );
    s
}
