#include <math.h>
#include "simple_pendulum.h"
const simple_pendulum_parameters simple_pendulum_default_parameters = {1.0, 1.0, 9.81};
void simple_pendulum_initial_state(const simple_pendulum_parameters *p, double *y) { (void)p; y[0] = 0.5; y[1] = 0.0; }
int simple_pendulum_rhs(double t, const double *y, const simple_pendulum_parameters *p, const double *u, double *dy) {
    (void)t; (void)u; dy[0] = y[1]; dy[1] = -p->g / p->L * sin(y[0]); return 0;
}
int simple_pendulum_outputs(double t, const double *y, const simple_pendulum_parameters *p, const double *u, double *out) {
    (void)t; (void)y; (void)p; (void)u; (void)out; return 0;
}
int simple_pendulum_energies(double t, const double *y, const simple_pendulum_parameters *p, const double *u, double *ke_pe) {
    (void)t; (void)u; ke_pe[0] = 0.5 * p->m * p->L * p->L * y[1] * y[1]; ke_pe[1] = -p->m * p->g * p->L * cos(y[0]); return 0;
}
