//! The second phase of a derivation: kinetic and potential energy, the Lagrangian and the
//! Rayleigh dissipation, first in all declared coordinates.

use std::collections::HashMap;

use cas::{ExprId, Pool, SymId};
use model::{Model, Rotation};

/// The scalar functions the equations of motion come from.
#[derive(Clone, Copy, Debug)]
pub(super) struct Energies {
    pub kinetic: ExprId,
    pub potential: ExprId,
    /// T − V and the scene's own Lagrangian terms.
    pub lagrangian: ExprId,
    /// Rayleigh's D, whose −∂D/∂q̇ is a generalized force.
    pub dissipation: ExprId,
}

/// ½·m·|ṙ|² of a body's centre, built one way for `energies` and the structural rows alike
/// (which must find the very term in L to take it out).
pub(super) fn translational_kinetic(pool: &mut Pool, body: &model::Body) -> ExprId {
    let mut v2 = Vec::new();
    for x in &body.position {
        let v = pool.time_derivative(*x);
        v2.push(pool.powi(v, 2));
    }
    let speed2 = pool.add(&v2);
    let t = pool.mul2(body.mass, speed2);
    pool.scale(t, &cas::number::ratio(1, 2))
}

/// ½·I·θ̇² of a body turning in the plane, built one way like [`translational_kinetic`].
pub(super) fn planar_kinetic(pool: &mut Pool, inertia: ExprId, angle: ExprId) -> ExprId {
    let w = pool.time_derivative(angle);
    let w2 = pool.powi(w, 2);
    let t = pool.mul2(inertia, w2);
    pool.scale(t, &cas::number::ratio(1, 2))
}

/// ½·ωᵀ·I·ω of a body turning in space (ω in body axes), built one way like
/// [`translational_kinetic`].
pub(super) fn spatial_kinetic(
    pool: &mut Pool,
    inertia: &[[ExprId; 3]; 3],
    w: [ExprId; 3],
) -> ExprId {
    let mut parts = Vec::new();
    for (i, row) in inertia.iter().enumerate() {
        for (j, entry) in row.iter().enumerate() {
            parts.push(pool.mul(&[w[i], *entry, w[j]]));
        }
    }
    let t = pool.add(&parts);
    pool.scale(t, &cas::number::ratio(1, 2))
}

/// T of every body (translation and, for a rigid body, rotation), V of gravity and the scene's
/// potentials, and L = T − V + the scene's Lagrangian terms, in all declared coordinates.
pub(super) fn energies(pool: &mut Pool, model: &Model) -> Energies {
    let dim = model.dimension();
    let mut kinetic_terms = Vec::new();
    let mut potential_terms = Vec::new();
    let gravity_dir: Option<Vec<ExprId>> = model.gravity.as_ref().map(|g| match &g.direction {
        // `along` gives a direction only: gravity's strength is g whatever the vector's length.
        Some(d) => {
            let squares: Vec<ExprId> = d.iter().map(|x| pool.powi(*x, 2)).collect();
            let norm2 = pool.add(&squares);
            let norm = pool.sqrt(norm2);
            d.iter().map(|x| pool.div(*x, norm)).collect()
        }
        None => {
            let mut d = vec![pool.zero(); dim];
            d[dim - 1] = pool.int(-1);
            d
        }
    });
    for body in &model.bodies {
        kinetic_terms.push(translational_kinetic(pool, body));
        match &body.rotation {
            None => {}
            Some(Rotation::Planar { inertia, angle }) => {
                kinetic_terms.push(planar_kinetic(pool, *inertia, *angle));
            }
            Some(rotation @ Rotation::Spatial { inertia, .. }) => {
                let w = rotation.spatial_angular_velocity(pool, false).expect("in space");
                kinetic_terms.push(spatial_kinetic(pool, inertia, w));
            }
        }
        if let (Some(g), Some(dir)) = (&model.gravity, &gravity_dir) {
            // V = −m g (d · r): the work gravity does is lost as potential energy.
            let parts: Vec<ExprId> =
                body.position.iter().zip(dir.iter()).map(|(x, d)| pool.mul2(*x, *d)).collect();
            let along = pool.add(&parts);
            let v = pool.mul(&[body.mass, g.strength, along]);
            potential_terms.push(pool.neg(v));
        }
    }
    for p in &model.potentials {
        potential_terms.push(p.expr);
    }
    let kinetic = pool.add(&kinetic_terms);
    let potential = pool.add(&potential_terms);
    let mut lag_terms = vec![kinetic, pool.neg(potential)];
    lag_terms.extend(model.lagrangians.iter().map(|l| l.expr));
    let lagrangian = pool.add(&lag_terms);
    let dissipation = {
        let d: Vec<ExprId> = model.dissipation.iter().map(|d| d.expr).collect();
        pool.add(&d)
    };
    Energies { kinetic, potential, lagrangian, dissipation }
}

impl Energies {
    /// T, V and L with the eliminated coordinates replaced by their solutions. D stays as it
    /// is: the generalized forces substitute into it themselves, in whichever coordinates
    /// they are taken.
    pub fn reduced(&self, pool: &mut Pool, elimination_map: &HashMap<SymId, ExprId>) -> Energies {
        Energies {
            kinetic: pool.subst(self.kinetic, elimination_map),
            potential: pool.subst(self.potential, elimination_map),
            lagrangian: pool.subst(self.lagrangian, elimination_map),
            dissipation: self.dissipation,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::eliminate::{eliminate_constraints, remaining_coordinates};
    use super::super::testing::{ascii, scene, FALLING_ROD};
    use super::*;

    #[test]
    fn a_pendulum() {
        let (mut pool, model) = scene(
            "param m, L, g\ncoord theta\nparticle bob { mass m; position (L*sin(theta), -L*cos(theta)) }\ngravity g",
        );
        let e = energies(&mut pool, &model);
        assert_eq!(
            ascii(&pool, e.kinetic),
            "1/2*m*(L^2*sin(theta)^2*theta'^2 + L^2*cos(theta)^2*theta'^2)"
        );
        assert_eq!(ascii(&pool, e.potential), "-m*L*g*cos(theta)");
        assert_eq!(
            ascii(&pool, e.lagrangian),
            "1/2*m*(L^2*sin(theta)^2*theta'^2 + L^2*cos(theta)^2*theta'^2) + m*L*g*cos(theta)"
        );
        assert_eq!(ascii(&pool, e.dissipation), "0");
    }

    /// A body turning in space, built in the model directly (the language does not write one
    /// yet): a gimbal that turns by phi about z, then by theta about the new x axis.
    #[test]
    fn a_spatial_body_turns_with_omega_from_its_orientation() {
        let (mut pool, mut model) = scene(
            "param m, A, B, C\ncoord phi\ncoord theta\nparticle g { mass m; position (0, 0, 0) }",
        );
        let sym = |pool: &mut Pool, name: &str| {
            let s = pool.lookup_symbol(name).expect("declared");
            pool.sym(s)
        };
        let (a, b, c) = (sym(&mut pool, "A"), sym(&mut pool, "B"), sym(&mut pool, "C"));
        let (phi, theta) = (sym(&mut pool, "phi"), sym(&mut pool, "theta"));
        let (zero, one) = (pool.zero(), pool.one());
        let rot_z = |pool: &mut Pool, q: ExprId| {
            let (s, k) = (pool.sin(q), pool.cos(q));
            let ms = pool.neg(s);
            [[k, ms, zero], [s, k, zero], [zero, zero, one]]
        };
        let rot_x = |pool: &mut Pool, q: ExprId| {
            let (s, k) = (pool.sin(q), pool.cos(q));
            let ms = pool.neg(s);
            [[one, zero, zero], [zero, k, ms], [zero, s, k]]
        };
        let (rz, rx) = (rot_z(&mut pool, phi), rot_x(&mut pool, theta));
        let mut orientation = [[zero; 3]; 3];
        for i in 0..3 {
            for j in 0..3 {
                let terms: Vec<ExprId> = (0..3).map(|k| pool.mul2(rz[i][k], rx[k][j])).collect();
                orientation[i][j] = pool.add(&terms);
            }
        }
        let inertia = [[a, zero, zero], [zero, b, zero], [zero, zero, c]];
        let w = model::kinematics::angular_velocity_in_body_axes(&mut pool, &orientation);
        let w: Vec<String> = w.iter().map(|e| ascii(&pool, *e)).collect();
        assert_eq!(w, ["theta'", "sin(theta)*phi'", "cos(theta)*phi'"]);
        model.bodies[0].rotation =
            Some(Rotation::Spatial { inertia, orientation, euler_parameters: None });
        assert_eq!(model.bodies[0].kind(), model::BodyKind::Spatial);
        let e = energies(&mut pool, &model);
        let kinetic = pool.simplify(e.kinetic);
        assert_eq!(
            ascii(&pool, kinetic),
            "1/2*B*sin(theta)^2*phi'^2 + 1/2*C*cos(theta)^2*phi'^2 + 1/2*A*theta'^2"
        );
    }

    #[test]
    fn a_rigid_body_turns_too() {
        let (mut pool, model) =
            scene("param m, I\ncoord x\ncoord phi\nbody wheel { mass m; inertia I; position (x, 0); angle phi }");
        let e = energies(&mut pool, &model);
        assert_eq!(ascii(&pool, e.kinetic), "1/2*m*x'^2 + 1/2*I*phi'^2");
        assert_eq!(ascii(&pool, e.potential), "0");
    }

    #[test]
    fn gravity_along_a_vector_keeps_its_strength() {
        let (mut pool, model) = scene(
            "param m, g\ncoord x\ncoord y\nparticle p { mass m; position (x, y) }\ngravity g along (3, -4)",
        );
        let e = energies(&mut pool, &model);
        assert_eq!(ascii(&pool, e.potential), "-m*g*(3/5*x - 4/5*y)");
    }

    #[test]
    fn the_scene_adds_its_own_terms() {
        let (mut pool, model) = scene(
            "param m, k, c, b\ncoord x\nparticle p { mass m; position (x, 0) }\npotential k/2*x^2\nlagrangian b*x*x'\ndissipation c/2*x'^2",
        );
        let e = energies(&mut pool, &model);
        assert_eq!(ascii(&pool, e.potential), "1/2*k*x^2");
        assert_eq!(ascii(&pool, e.lagrangian), "1/2*m*x'^2 + b*x*x' - 1/2*k*x^2");
        assert_eq!(ascii(&pool, e.dissipation), "1/2*c*x'^2");
    }

    #[test]
    fn the_falling_rod_reduced() {
        let (mut pool, model) = scene(FALLING_ROD);
        let eliminated = eliminate_constraints(&mut pool, &model).eliminated;
        let coordinates = remaining_coordinates(&mut pool, &model, &eliminated);
        let full = energies(&mut pool, &model);
        assert_eq!(ascii(&pool, full.potential), "m*g*y");
        let reduced = full.reduced(&mut pool, &coordinates.elimination_map);
        assert_eq!(
            ascii(&pool, reduced.kinetic),
            "1/2*m*(x'^2 + 1/4*L^2*sin(theta)^2*theta'^2) + 1/24*m*L^2*theta'^2"
        );
        assert_eq!(ascii(&pool, reduced.potential), "1/2*m*L*g*cos(theta)");
        assert_eq!(reduced.dissipation, full.dissipation);
    }
}
