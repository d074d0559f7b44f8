/* Hand-written stand-in for `lagrange codegen --lang c examples/classics/simple_pendulum.lag`,
 * to be deleted once that lands. */
#ifndef SIMPLE_PENDULUM_H
#define SIMPLE_PENDULUM_H
#define simple_pendulum_COORDINATES 1
#define simple_pendulum_STATES 2
#define simple_pendulum_CONSTRAINTS 0
#define simple_pendulum_PARAMETERS 3
#define simple_pendulum_INPUTS 0
#define simple_pendulum_OUTPUTS 0
typedef struct { double m; double L; double g; } simple_pendulum_parameters;
extern const simple_pendulum_parameters simple_pendulum_default_parameters;
void simple_pendulum_initial_state(const simple_pendulum_parameters *p, double *y);
int simple_pendulum_rhs(double t, const double *y, const simple_pendulum_parameters *p, const double *u, double *dy);
int simple_pendulum_outputs(double t, const double *y, const simple_pendulum_parameters *p, const double *u, double *out);
int simple_pendulum_energies(double t, const double *y, const simple_pendulum_parameters *p, const double *u, double *ke_pe);
#endif
