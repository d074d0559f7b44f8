//! Contacts in a derivation: which are closed at the start, the rows of every contact for a
//! run, and the impact law of each, derived exactly.
//!
//! A contact's rows are built as any kept constraint's (a position row on its gap, a velocity
//! row for its grip). What the derivation's equations show is the mode at the start: the
//! two-sided constraints and the contacts closed there (gap and its rate both zero at the
//! start). Every contact, closed or not, is in [`Derivation::contacts`], from which a run takes
//! them all ([`Derivation::with_every_contact`]) and opens and closes them as it goes.

use cas::number::Signed;
use cas::{linear_system, ExprId};
use lang::Diagnostic;

use crate::{Derivation, Multiplier};

/// One contact's rows in a derivation.
#[derive(Clone, Debug)]
pub struct ContactRows {
    /// Its index in the model's contacts.
    pub contact: usize,
    /// The row on its gap g(q, t) ≥ 0, with the multiplier that is its normal reaction.
    pub normal: Multiplier,
    /// The row of its grip (a tangential rate held at zero while closed), if it grips.
    pub grip: Option<Multiplier>,
    /// A rough contact in space: the row of its second tangential rate.
    pub cross: Option<Multiplier>,
    /// Newton's coefficient e.
    pub restitution: ExprId,
    /// Whether its gap and the gap's rate are zero at the start: the derivation's equations
    /// then hold it closed.
    pub closed_at_start: bool,
}

/// Where a run finds a contact among its multipliers.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ContactSlots {
    pub normal: usize,
    pub grip: Option<usize>,
    /// A rough contact in space: its second tangential row, after its grip's.
    pub cross: Option<usize>,
}

/// The impact law of one contact landing alone, with the two-sided constraints kept:
/// Λ = −D⁻¹·c with D = W·U (W the contact's rows, U the augmented system's response to them)
/// and c = ((1 + e)·γ⁻, γ_T⁻); then q̇⁺ = q̇⁻ + U·Λ. The rates in these expressions are the
/// ones before the impact.
#[derive(Clone, Debug)]
pub struct ImpactLaw {
    /// γ⁻ = ∂g/∂q·q̇⁻ + ∂g/∂t: the normal rate before the impact.
    pub normal_rate: ExprId,
    /// The normal impulse Λ.
    pub impulse: ExprId,
    /// The tangential impulse of a grip.
    pub tangential_impulse: Option<ExprId>,
    /// In space, the tangential impulse along the second rate.
    pub cross_impulse: Option<ExprId>,
    /// q̇⁺ of each remaining coordinate, in the derivation's order.
    pub rates_after: Vec<ExprId>,
    /// D = W·U: the inverse inertia the contact's rows meet (1/m for a ball on a floor).
    pub delassus: Vec<Vec<ExprId>>,
    /// q̇⁺ = q̇⁻ + U·Λ with the impulses as the symbols Λ (and Λ_T): how a hand derivation
    /// writes the rates after when the impulses put in make them long.
    pub rates_in_impulses: Vec<ExprId>,
}

/// Past this many unknowns (coordinates and two-sided multipliers) the impact law is left to
/// numbers: a symbolic inverse of the augmented system grows too large to print.
const IMPACT_LAW_LIMIT: usize = 6;

impl Derivation {
    /// Takes the contacts' rows out of the multipliers into [`Derivation::contacts`], keeping
    /// among the multipliers those of contacts closed at the start.
    /// A contact whose gap is negative at the start is an error: the scene starts inside it.
    pub(crate) fn separate_contacts(&mut self) -> Result<(), Vec<Diagnostic>> {
        if self.model.contacts.is_empty() {
            return Ok(());
        }
        let mut errors = Vec::new();
        let state = self.initial_state();
        let mut contacts = Vec::new();
        for (k, contact) in self.model.contacts.clone().into_iter().enumerate() {
            let find = |d: &Derivation, c: usize| {
                d.multipliers.iter().find(|m| m.constraint == c).cloned()
            };
            let Some(normal) = find(self, contact.normal) else { continue };
            let grip = contact.grip.and_then(|g| find(self, g));
            let cross = contact.cross.and_then(|g| find(self, g));
            let gap = self.model.pool.subst(normal.rows.phi(), &state);
            let rate = self.model.pool.subst(normal.rows.velocity, &state);
            let values = self.parameter_values();
            let at_values = self.model.pool.subst(gap, &values);
            // Decided here where the gap is a rational at the start; a run decides the rest.
            if let Some(g) = self.model.pool.as_num(at_values).cloned() {
                // An armed contact may start inside its gap: disarmed, or armed below it.
                if g.is_negative() && contact.armed.is_none() {
                    errors.push(
                        Diagnostic::error(
                            contact.span,
                            format!("the scene starts inside `{}`", contact.name),
                        )
                        .with_label(format!("its gap is {g} at the start, not at least 0"))
                        .with_hint(
                            "give start positions on the open side of the contact, or touching it",
                        ),
                    );
                }
            }
            let closed_at_start =
                self.zero_at_parameter_values(gap) && self.zero_at_parameter_values(rate);
            contacts.push(ContactRows {
                contact: k,
                normal,
                grip,
                cross,
                restitution: contact.restitution,
                closed_at_start,
            });
        }
        let mut open: Vec<usize> = contacts
            .iter()
            .filter(|c| !c.closed_at_start)
            .flat_map(|c| {
                std::iter::once(c.normal.constraint)
                    .chain(c.grip.iter().chain(&c.cross).map(|g| g.constraint))
            })
            .collect();
        // A rough contact closed at the start sticks there if its tangential rate is zero (its
        // row held, as a grip's) and otherwise slips: its row is then no constraint, and
        // Coulomb's force −μ·s·λ·J_T rides on the normal one, s the sign of the rate.
        let mut bent = Vec::new();
        for c in &contacts {
            let (Some(mu), Some(grip)) = (self.model.contacts[c.contact].friction, &c.grip) else {
                continue;
            };
            if !c.closed_at_start {
                continue;
            }
            if let Some(cross) = &c.cross {
                // In space the slip's direction is the tangential velocity's, γ_T/‖γ_T‖, and
                // the force −μ·λ·(γ₁·J₁ + γ₂·J₂)/‖γ_T‖ rides on the normal one.
                let rates = [grip, cross].map(|g| self.model.pool.subst(g.rows.velocity, &state));
                if rates.iter().all(|r| self.zero_at_parameter_values(*r)) {
                    continue;
                }
                open.push(grip.constraint);
                open.push(cross.constraint);
                let pool = &mut self.model.pool;
                let squares: Vec<ExprId> = rates.iter().map(|r| pool.mul2(*r, *r)).collect();
                let sum = pool.add(&squares);
                let size = pool.sqrt(sum);
                let minus_mu = pool.neg(mu);
                let factors = rates.map(|r| {
                    let over = pool.div(r, size);
                    pool.mul2(minus_mu, over)
                });
                let direction: Vec<ExprId> = (0..c.normal.rows.jacobian.len())
                    .map(|i| {
                        let along = [grip, cross]
                            .iter()
                            .zip(&factors)
                            .map(|(g, f)| pool.mul2(*f, g.rows.jacobian[i]))
                            .collect::<Vec<_>>();
                        let mut terms = vec![c.normal.rows.jacobian[i]];
                        terms.extend(along);
                        let sum = pool.add(&terms);
                        pool.simplify(sum)
                    })
                    .collect();
                bent.push((c.normal.constraint, direction));
                continue;
            }
            let rate = self.model.pool.subst(grip.rows.velocity, &state);
            if self.zero_at_parameter_values(rate) {
                continue;
            }
            let values = self.parameter_values();
            let at_values = self.model.pool.subst(rate, &values);
            let Some(sign) = self.model.pool.sign_of_constant(at_values).map(i64::from) else {
                errors.push(
                    Diagnostic::error(
                        self.model.contacts[c.contact].span,
                        format!(
                            "the sign of `{}`'s slip at the start is not decided",
                            self.model.contacts[c.contact].name
                        ),
                    )
                    .with_label("its tangential rate at the start is no number")
                    .with_hint("give the start's rates as numbers, or expressions of parameters"),
                );
                continue;
            };
            open.push(grip.constraint);
            let pool = &mut self.model.pool;
            let sign = pool.num(cas::number::int(-sign));
            let factor = pool.mul2(mu, sign);
            let direction: Vec<ExprId> = c
                .normal
                .rows
                .jacobian
                .iter()
                .zip(&grip.rows.jacobian)
                .map(|(n, t)| {
                    let along = pool.mul2(factor, *t);
                    let sum = pool.add(&[*n, along]);
                    pool.simplify(sum)
                })
                .collect();
            bent.push((c.normal.constraint, direction));
        }
        self.multipliers.retain(|m| !open.contains(&m.constraint));
        for m in &mut self.multipliers {
            if let Some((_, direction)) = bent.iter().find(|(c, _)| *c == m.constraint) {
                m.force = Some(direction.clone());
            }
        }
        self.contacts = contacts;
        if errors.is_empty() {
            Ok(())
        } else {
            Err(errors)
        }
    }

    /// Makes the multipliers those a run integrates: the two-sided constraints, then each
    /// contact's normal row and its grip's, open or closed. Returns where each contact is.
    pub fn with_every_contact(&mut self) -> Vec<ContactSlots> {
        let model = &self.model;
        self.multipliers.retain(|m| !model.constraints[m.constraint].kind.is_unilateral());
        let mut slots = Vec::new();
        for c in &self.contacts {
            let normal = self.multipliers.len();
            self.multipliers.push(c.normal.clone());
            let grip = c.grip.as_ref().map(|g| {
                self.multipliers.push(g.clone());
                normal + 1
            });
            let cross = c.cross.as_ref().map(|g| {
                self.multipliers.push(g.clone());
                normal + 2
            });
            slots.push(ContactSlots { normal, grip, cross });
        }
        self.solved = None;
        slots
    }

    /// The impact law of contact `k` landing alone, exactly; `None` when the system is too
    /// large to solve symbolically (past six unknowns) or singular.
    pub fn impact_law(&mut self, k: usize) -> Option<ImpactLaw> {
        let contact = self.contacts.get(k)?.clone();
        let n = self.coords.len();
        let kept: Vec<Multiplier> = self
            .multipliers
            .iter()
            .filter(|m| !self.model.constraints[m.constraint].kind.is_unilateral())
            .cloned()
            .collect();
        let size = n + kept.len();
        if size > IMPACT_LAW_LIMIT {
            return None;
        }
        let pool = &mut self.model.pool;
        // The augmented system [M −J_Eᵀ; J_E 0] of the kept two-sided constraints.
        let mut system: Vec<Vec<ExprId>> = Vec::with_capacity(size);
        for i in 0..n {
            let mut row = self.mass_matrix[i].clone();
            for m in &kept {
                let j = m.rows.jacobian[i];
                row.push(pool.neg(j));
            }
            system.push(row);
        }
        for m in &kept {
            let mut row = m.rows.jacobian.clone();
            row.extend(std::iter::repeat_n(pool.zero(), kept.len()));
            system.push(row);
        }
        let rows: Vec<&Multiplier> = std::iter::once(&contact.normal)
            .chain(contact.grip.as_ref())
            .chain(&contact.cross)
            .collect();
        // U: the rates' response to a unit impulse along each of the contact's rows.
        let mut response: Vec<Vec<ExprId>> = Vec::new();
        for r in &rows {
            let mut rhs = r.rows.jacobian.clone();
            rhs.extend(std::iter::repeat_n(pool.zero(), kept.len()));
            let x = linear_system::solve(pool, &system, &rhs)?;
            response.push(x[..n].to_vec());
        }
        // D = W·U, the contact's Delassus matrix.
        let delassus: Vec<Vec<ExprId>> = rows
            .iter()
            .map(|r| {
                response
                    .iter()
                    .map(|u| {
                        let terms: Vec<ExprId> =
                            (0..n).map(|i| pool.mul2(r.rows.jacobian[i], u[i])).collect();
                        let d = pool.add(&terms);
                        tidy(pool, d)
                    })
                    .collect()
            })
            .collect();
        let one = pool.one();
        let e1 = pool.add2(one, contact.restitution);
        let normal_rate = pool.simplify(contact.normal.rows.velocity);
        let mut target = vec![pool.mul2(e1, normal_rate)];
        for g in contact.grip.iter().chain(&contact.cross) {
            target.push(g.rows.velocity);
        }
        let negated: Vec<ExprId> = target.iter().map(|t| pool.neg(*t)).collect();
        let impulses = linear_system::solve(pool, &delassus, &negated)?;
        let impulses: Vec<ExprId> = impulses.into_iter().map(|x| tidy(pool, x)).collect();
        let impulse_symbols: Vec<cas::SymId> =
            ["Λ", "Λ_T", "Λ_T2"].iter().take(impulses.len()).map(|name| pool.param(name)).collect();
        let symbols: Vec<ExprId> = impulse_symbols.iter().map(|s| pool.sym(*s)).collect();
        let mut rates_after = Vec::with_capacity(n);
        let mut rates_in_impulses = Vec::with_capacity(n);
        for i in 0..n {
            let rate = pool.sym(self.rates[i]);
            let mut exact = vec![rate];
            let mut named = vec![rate];
            for ((u, l), s) in response.iter().zip(&impulses).zip(&symbols) {
                exact.push(pool.mul2(u[i], *l));
                // Each response on its own, so that the sum reads q̇ + U·Λ term by term.
                let scaled = tidy(pool, u[i]);
                named.push(pool.mul2(scaled, *s));
            }
            let exact = pool.add(&exact);
            rates_after.push(tidy(pool, exact));
            rates_in_impulses.push(pool.add(&named));
        }
        Some(ImpactLaw {
            normal_rate,
            impulse: impulses[0],
            tangential_impulse: impulses.get(1).copied(),
            cross_impulse: impulses.get(2).copied(),
            rates_after,
            delassus,
            rates_in_impulses,
        })
    }
}

/// A rational expression as a hand derivation leaves it: over one denominator, its monomial
/// factors cancelled, the numerator simplified, and each side's common factor taken out
/// (−m·(1 + e)·ẏ, and (b² + h²) rather than m·b² + m·h² under a fraction bar).
fn tidy(pool: &mut cas::Pool, e: ExprId) -> ExprId {
    let one = pool.one();
    let q = linear_system::quotient(pool, e, one);
    let (coefficient, factors) = pool.factors(q);
    let (mut above, mut below) = (Vec::new(), Vec::new());
    for (base, exponent) in factors {
        if exponent.is_negative() {
            below.push((base, -exponent));
        } else {
            above.push((base, exponent));
        }
    }
    let numerator = pool.product(&coefficient, &above);
    let numerator = pool.simplify(numerator);
    let numerator = pool.factor_content(numerator);
    let unit = cas::Rational::from_integer(1.into());
    let denominator = pool.product(&unit, &below);
    let denominator = pool.factor_content(denominator);
    pool.div(numerator, denominator)
}
