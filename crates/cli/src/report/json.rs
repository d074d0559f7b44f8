//! The JSON report, for programs: every expression a string in the scene syntax.

use super::*;

/// The report as JSON; every expression is a string in the scene syntax.
pub fn json(d: &mut Derivation) -> String {
    render(d, |d| JsonReport { d, pool: &d.model.pool, fields: Map::new() })
}

/// The JSON report's keys, in the order it prints them.
const JSON_KEYS: [&str; 19] = [
    "scene",
    "coordinates",
    "parameters",
    "inputs",
    "outputs",
    "constraints",
    "contacts",
    "kinetic_energy",
    "potential_energy",
    "equations",
    "mass_matrix",
    "forcing",
    "reactions",
    "reactions_with_accelerations",
    "shown",
    "at_start",
    "model",
    // Only scenes that keep a velocity constraint and ask for no contact force have this form.
    "independent_rates",
    // Numbers rather than exact expressions: how far to trust them.
    "at_start_significant_digits",
];

/// The JSON report: each section sets its keys, printed in the order of [`JSON_KEYS`].
struct JsonReport<'a> {
    d: &'a Derivation,
    pool: &'a Pool,
    fields: Map<String, Json>,
}

const A: Style = Style::Ascii;

impl Renderer for JsonReport<'_> {
    fn section(&mut self, section: &Section) {
        let (d, pool) = (self.d, self.pool);
        let name = |s: SymId| pool.symbol(s).name.clone();
        let prints = |es: &[ExprId]| es.iter().map(|e| pool.print(*e, A)).collect::<Vec<_>>();
        let names = |ss: &[(SymId, ExprId)]| -> Map<String, Json> {
            ss.iter().map(|(s, e)| (name(*s), json!(pool.print(*e, A)))).collect()
        };
        let mut set = |key: &str, value: Json| {
            self.fields.insert(key.into(), value);
        };
        match section {
            Section::Title(title) => set("scene", json!(title)),
            Section::Parameters(params) => set("parameters", json_parameters(pool, params)),
            // Only a scene with signals has these keys, so that others read as before.
            Section::Signals { inputs, outputs } => {
                if !inputs.is_empty() {
                    set("inputs", json_inputs(pool, inputs));
                }
                if !outputs.is_empty() {
                    let outputs =
                        outputs.iter().map(|o| (o.name.clone(), json!(pool.print(o.value, A))));
                    set("outputs", Json::Object(outputs.collect()));
                }
            }
            Section::Coordinates { generalized, .. } => {
                set("coordinates", json!(generalized.iter().map(|s| name(*s)).collect::<Vec<_>>()))
            }
            Section::Constraints { constraints, .. } => {
                set("constraints", json_constraints(d, constraints))
            }
            // Only a scene with contacts has this key.
            Section::Contacts([]) => {}
            Section::Contacts(contacts) => {
                let rates: Vec<String> = d.rates.iter().map(|s| name(*s)).collect();
                let list: Vec<Json> = contacts
                    .iter()
                    .map(|c| {
                        let impact = c.impact.as_ref().map(|law| {
                            let after: Map<String, Json> = rates
                                .iter()
                                .zip(&law.rates_after)
                                .map(|(r, e)| (r.clone(), json!(pool.print(*e, A))))
                                .collect();
                            json!({
                                "normal_rate": pool.print(law.normal_rate, A),
                                "impulse": pool.print(law.impulse, A),
                                "tangential_impulse": law.tangential_impulse.map(|t| pool.print(t, A)),
                                "rates_after": after,
                            })
                        });
                        let mut contact = json!({
                            "name": c.name,
                            "gap": pool.print(c.gap, A),
                            "restitution": pool.print(c.restitution, A),
                            "grip": c.grip.map(|g| pool.print(g, A)),
                            "closed_at_start": c.closed_at_start,
                            "direction": prints(&c.direction),
                            "bias": pool.print(c.bias, A),
                            "impact": impact,
                        });
                        // A rough contact's coefficient, its tangential rate being `grip`'s.
                        if let Some(mu) = c.friction {
                            contact["friction"] = json!(pool.print(mu, A));
                        }
                        if let Some(armed) = c.armed {
                            contact["armed"] = json!(pool.print(armed, A));
                        }
                        // In space, its second tangential rate: the cone acts on (grip, cross).
                        if let Some((v, _, _)) = &c.cross {
                            contact["cross"] = json!(pool.print(*v, A));
                            if let Some(law) = &c.impact {
                                contact["impact"]["cross_impulse"] =
                                    json!(law.cross_impulse.map(|t| pool.print(t, A)));
                            }
                        }
                        contact
                    })
                    .collect();
                set("contacts", Json::Array(list));
            }
            Section::Energies { kinetic, potential, .. } => {
                set("kinetic_energy", json!(pool.print(*kinetic, A)));
                set("potential_energy", json!(pool.print(*potential, A)));
            }
            Section::Equations(equations) => set(
                "equations",
                equations
                    .iter()
                    .map(|e| json!({"lhs": pool.print(e.lhs, A), "rhs": pool.print(e.rhs, A)}))
                    .collect(),
            ),
            Section::MassMatrix { mass, forcing, .. } => {
                set("mass_matrix", json!(mass.iter().map(|r| prints(r)).collect::<Vec<_>>()));
                set("forcing", json!(prints(forcing)));
            }
            Section::Independent(form) => {
                let dependent: Map<String, Json> = form
                    .dependent
                    .iter()
                    .map(|(r, e)| (name(*r), Json::String(pool.print(*e, A))))
                    .collect();
                set(
                    "independent_rates",
                    json!({
                        "independent": form.independent.iter().map(|r| name(*r)).collect::<Vec<_>>(),
                        "dependent": dependent,
                        "equations": prints(&form.equations),
                    }),
                );
            }
            Section::Reactions { reactions, of_state } => {
                set("reactions", Json::Object(names(of_state)));
                set("reactions_with_accelerations", Json::Object(names(reactions)));
            }
            Section::Shown(shown) => {
                let shown: Map<String, Json> = shown
                    .iter()
                    .map(|(show, v)| (show.label.clone(), value_json(pool, v)))
                    .collect();
                set("shown", Json::Object(shown));
            }
            Section::AtStart { at_start, .. } => {
                let label = |show: &model::Show| show.label.clone();
                let values: Map<String, Json> = match at_start {
                    ShownAtStart::Exact(items) => {
                        items.iter().map(|(show, v)| (label(show), value_json(pool, v))).collect()
                    }
                    ShownAtStart::Numeric { items, digits, .. } => {
                        set("at_start_significant_digits", json!(digits));
                        items.iter().map(|(show, v)| (label(show), numeric_json(v))).collect()
                    }
                    ShownAtStart::Unvalued { .. } | ShownAtStart::Singular => Map::new(),
                };
                set("at_start", Json::Object(values));
            }
            Section::Model => set("model", model_json(d)),
        }
    }

    fn finish(mut self) -> String {
        let mut doc = Map::new();
        for key in JSON_KEYS {
            if let Some(value) = self.fields.remove(key) {
                doc.insert(key.into(), value);
            }
        }
        debug_assert!(self.fields.is_empty(), "a JSON key missing from JSON_KEYS");
        let mut text = serde_json::to_string_pretty(&Json::Object(doc)).unwrap_or_default();
        text.push('\n');
        text
    }
}

/// The parameters, each with its value as written and in numbers, and its unit.
fn json_parameters(pool: &Pool, params: &[model::Param]) -> Json {
    let mut out = Map::new();
    for p in params {
        let numeric = p.value.map(|v| numeric::eval(pool, v, &[])).filter(|x| x.is_finite());
        out.insert(
            p.name.clone(),
            json!({
                "value": p.value.map(|v| pool.print(v, A)),
                "numeric": numeric,
                "unit": p.unit.as_ref().map(|u| unit_text(u, A)),
            }),
        );
    }
    Json::Object(out)
}

fn json_inputs(pool: &Pool, inputs: &[model::Input]) -> Json {
    let inputs = inputs.iter().map(|u| {
        let numeric = Some(numeric::eval(pool, u.value, &[])).filter(|x| x.is_finite());
        let unit = u.unit.as_ref().map(|u| unit_text(u, A));
        (
            u.name.clone(),
            json!({ "value": pool.print(u.value, A), "numeric": numeric, "unit": unit }),
        )
    });
    Json::Object(inputs.collect())
}

/// Each constraint with how it was treated.
fn json_constraints(d: &Derivation, constraints: &[model::Constraint]) -> Json {
    let pool = &d.model.pool;
    let name = |s: SymId| pool.symbol(s).name.clone();
    let constraints: Vec<Json> = constraints
            .iter()
            .enumerate()
            .map(|(i, c)| {
                let equation = format!("{} = {}", pool.print(c.lhs, A), pool.print(c.rhs, A));
                if let Some(e) = d.eliminated.iter().find(|e| e.constraint == i) {
                    json!({
                        "name": c.name,
                        "equation": equation,
                        "treatment": "eliminated",
                        "coordinate": name(e.coord),
                        "solution": pool.print(e.solution, A),
                    })
                } else {
                    let m = d.multipliers.iter().find(|m| m.constraint == i);
                    let mut entry = json!({
                        "name": c.name,
                        "equation": equation,
                        "treatment": "multiplier",
                        "multiplier": name(c.force_symbol),
                        "jacobian": m.map(|m| m.rows.jacobian.iter().map(|e| pool.print(*e, A)).collect::<Vec<_>>()),
                        "bias": m.map(|m| pool.print(m.rows.bias, A)),
                    });
                    // A slipping contact's force, bent off its row by friction.
                    if let Some(force) = m.and_then(|m| m.force.as_ref()) {
                        let force: Vec<String> = force.iter().map(|e| pool.print(*e, A)).collect();
                        entry["force_direction"] = json!(force);
                    }
                    entry
                }
            })
            .collect();
    Json::Array(constraints)
}

/// The scene's primitive data (before any derivation), so that an independent tool can derive
/// the equations from the same system: every declared coordinate, the bodies, gravity, the
/// energy and dissipation terms, the loads, and each constraint with how it was treated.
fn model_json(d: &Derivation) -> Json {
    let m = &d.model;
    let pool = &m.pool;
    let a = Style::Ascii;
    let name = |s: SymId| pool.symbol(s).name.clone();
    let print = |e: ExprId| pool.print(e, a);
    let prints = |es: &[ExprId]| es.iter().map(|e| pool.print(*e, a)).collect::<Vec<_>>();
    let bodies: Vec<Json> = m
        .bodies
        .iter()
        .map(|b| {
            let matrix = |m: &[[ExprId; 3]; 3]| -> Vec<Vec<String>> {
                m.iter().map(|r| prints(r)).collect()
            };
            match &b.rotation {
                // A planar body is "rigid" in the JSON that the SymPy cross-check reads.
                None | Some(model::Rotation::Planar { .. }) => json!({
                    "name": b.name,
                    "kind": if b.rotation.is_some() { "rigid" } else { "particle" },
                    "mass": print(b.mass),
                    "inertia": b.planar_inertia().map(print),
                    "position": prints(&b.position),
                    "angle": b.angle().map(print),
                }),
                Some(model::Rotation::Spatial { inertia, orientation, euler_parameters }) => {
                    let mut o = json!({
                        "name": b.name,
                        "kind": "spatial",
                        "mass": print(b.mass),
                        "inertia": matrix(inertia),
                        "position": prints(&b.position),
                        "orientation": matrix(orientation),
                    });
                    if let Some(e) = euler_parameters {
                        o["euler_parameters"] = json!(prints(e));
                    }
                    o
                }
            }
        })
        .collect();
    let gravity = m.gravity.as_ref().map(|g| {
        json!({
            "strength": print(g.strength),
            // As written; null means the default, straight down (−y in 2D, −z in 3D).
            "direction": g.direction.as_ref().map(|v| prints(v)),
        })
    });
    let terms = |ts: &[model::Term]| ts.iter().map(|t| print(t.expr)).collect::<Vec<_>>();
    let loads = |ls: &[model::Load], key: &str| -> Vec<Json> {
        ls.iter()
            .map(|l| {
                let mut o = Map::new();
                o.insert("name".into(), json!(l.name));
                o.insert("body".into(), json!(m.bodies[l.body].name));
                let v = match &l.value {
                    Value::Scalar(e) => json!(print(*e)),
                    other => json!(prints(&other.entries())),
                };
                o.insert(key.into(), v);
                if let Some(at) = &l.at {
                    o.insert("at".into(), json!(prints(at)));
                }
                Json::Object(o)
            })
            .collect()
    };
    let constraints: Vec<Json> = m
        .constraints
        .iter()
        .enumerate()
        .map(|(i, c)| {
            let mut o = Map::new();
            o.insert("name".into(), json!(c.name));
            o.insert("phi".into(), json!(print(c.phi)));
            // A position constraint, the most common, goes without saying.
            if c.kind != model::ConstraintKind::Position {
                o.insert("kind".into(), json!(c.kind.name()));
            }
            o.insert("reaction".into(), json!(name(c.force_symbol)));
            if let Some(e) = d.eliminated.iter().find(|e| e.constraint == i) {
                o.insert("treatment".into(), json!("eliminated"));
                o.insert("coordinate".into(), json!(name(e.coord)));
                o.insert("solution".into(), json!(print(e.solution)));
            } else if let Some(k) = d.multipliers.iter().find(|k| k.constraint == i) {
                o.insert("treatment".into(), json!("multiplier"));
                o.insert("multiplier".into(), json!(name(k.lambda)));
            }
            Json::Object(o)
        })
        .collect();
    json!({
        "time": name(m.time),
        "coordinates": m.coords.iter().map(|c| c.name.clone()).collect::<Vec<_>>(),
        "bodies": bodies,
        "gravity": gravity,
        "potentials": terms(&m.potentials),
        "dissipation": terms(&m.dissipation),
        "lagrangian": terms(&m.lagrangians),
        "forces": loads(&m.forces, "vector"),
        "torques": loads(&m.torques, "torque"),
        "constraints": constraints,
    })
}
