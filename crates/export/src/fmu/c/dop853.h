/* The adaptive DOP853 pair that `lagrange simulate --method dop853` steps with, for the
 * Co-Simulation interface: the tableau comes from lagrange (dop853_tableau.h), the step
 * control is the one of lagrange's integrator, written again in C. */
#ifndef LAGRANGE_DOP853_H
#define LAGRANGE_DOP853_H

#include <stddef.h>

/* F(t, y) into dy; nonzero when it cannot be evaluated there. */
typedef int (*dop853_rhs)(void *context, double t, const double *y, double *dy);

typedef struct {
    size_t dim;
    double rtol, atol;
    /* The step to try next; 0 until the first one is chosen. */
    double h;
    /* Whether f holds F at the current point (the first stage of the next step). */
    int have_f;
    /* 13 rows of dim: the twelve stages, then F at the end of the step. */
    double *k;
    double *tmp, *y_new, *f;
    unsigned long evaluations, rejected;
} dop853_state;

enum { DOP853_OK = 0, DOP853_RHS_FAILED = 1, DOP853_STEP_TOO_SMALL = 2, DOP853_NO_MEMORY = 3 };

int dop853_init(dop853_state *s, size_t dim, double rtol, double atol,
                void *(*allocate)(size_t, size_t));
void dop853_free(dop853_state *s, void (*release)(void *));
/* Forget F at the current point: the state, a parameter or an input changed between steps. */
void dop853_restart(dop853_state *s);
/* Steps from *t to t_end exactly, updating y and *t; *t is where it stopped on failure. */
int dop853_integrate(dop853_state *s, dop853_rhs rhs, void *context, double *t, double *y,
                     double t_end);

#endif
