/* DOP853 with local extrapolation (the eighth-order solution propagates) and the error
 * estimate of Hairer, Nørsett and Wanner that blends the fifth- and third-order embedded
 * solutions; the starting step and the step-size factor are those of lagrange's integrator,
 * so a Co-Simulation step and `lagrange simulate` take the same steps between the same
 * points. */
#include <float.h>
#include <math.h>
#include <string.h>

#include "dop853.h"
#include "dop853_tableau.h"

int dop853_init(dop853_state *s, size_t dim, double rtol, double atol,
                void *(*allocate)(size_t, size_t)) {
    size_t n = dim > 0 ? dim : 1;
    memset(s, 0, sizeof *s);
    s->dim = dim;
    s->rtol = rtol;
    s->atol = atol;
    s->k = allocate(16 * n, sizeof(double));
    if (s->k == NULL) {
        return DOP853_NO_MEMORY;
    }
    s->tmp = s->k + 13 * n;
    s->y_new = s->k + 14 * n;
    s->f = s->k + 15 * n;
    return DOP853_OK;
}

void dop853_free(dop853_state *s, void (*release)(void *)) {
    if (s->k != NULL) {
        release(s->k);
    }
    s->k = NULL;
}

void dop853_restart(dop853_state *s) { s->have_f = 0; }

static double weighted_rms(const dop853_state *s, const double *v, const double *y) {
    double sum = 0.0;
    size_t i;
    if (s->dim == 0) {
        return 0.0;
    }
    for (i = 0; i < s->dim; i++) {
        double r = v[i] / (s->atol + fabs(y[i]) * s->rtol);
        sum += r * r;
    }
    return sqrt(sum / (double)s->dim);
}

/* Hairer's starting step, from the sizes of y, F and a trial Euler step. */
static int initial_step(dop853_state *s, dop853_rhs rhs, void *context, double t,
                        const double *y, double t_end, double *h) {
    size_t i, d = s->dim;
    double *f1 = s->k + 12 * d, d0, d1, d2, h0, h1;
    d0 = weighted_rms(s, y, y);
    d1 = weighted_rms(s, s->f, y);
    h0 = (d0 < 1e-5 || d1 < 1e-5) ? 1e-6 : 0.01 * d0 / d1;
    if (h0 > fabs(t_end - t)) {
        h0 = fabs(t_end - t);
    }
    for (i = 0; i < d; i++) {
        s->tmp[i] = y[i] + h0 * s->f[i];
    }
    if (rhs(context, t + h0, s->tmp, f1) != 0) {
        return DOP853_RHS_FAILED;
    }
    s->evaluations++;
    for (i = 0; i < d; i++) {
        s->tmp[i] = f1[i] - s->f[i];
    }
    d2 = weighted_rms(s, s->tmp, y) / h0;
    if (d1 <= 1e-15 && d2 <= 1e-15) {
        h1 = h0 * 1e-3 > 1e-6 ? h0 * 1e-3 : 1e-6;
    } else {
        h1 = pow(0.01 / (d1 > d2 ? d1 : d2), 1.0 / (DOP853_ORDER + 1.0));
    }
    *h = 100.0 * h0 < h1 ? 100.0 * h0 : h1;
    return DOP853_OK;
}

/* One trial step of size h from (t, y): the stages, y_new, F there; the error norm in *err. */
static int trial(dop853_state *s, dop853_rhs rhs, void *context, double t, const double *y,
                 double h, double *err) {
    size_t i, j, st, d = s->dim;
    double e5 = 0.0, e3 = 0.0, denom;
    for (st = 1; st < DOP853_STAGES; st++) {
        for (i = 0; i < d; i++) {
            double acc = 0.0;
            for (j = 0; j < st; j++) {
                acc += dop853_a[st][j] * s->k[j * d + i];
            }
            s->tmp[i] = y[i] + h * acc;
        }
        if (rhs(context, t + dop853_c[st] * h, s->tmp, s->k + st * d) != 0) {
            return DOP853_RHS_FAILED;
        }
        s->evaluations++;
    }
    for (i = 0; i < d; i++) {
        double acc = 0.0;
        for (j = 0; j < DOP853_STAGES; j++) {
            acc += dop853_b[j] * s->k[j * d + i];
        }
        s->y_new[i] = y[i] + h * acc;
    }
    if (rhs(context, t + h, s->y_new, s->k + DOP853_STAGES * d) != 0) {
        return DOP853_RHS_FAILED;
    }
    s->evaluations++;
    for (i = 0; i < d; i++) {
        double a5 = 0.0, a3 = 0.0, scale, r5, r3;
        double big = fabs(y[i]) > fabs(s->y_new[i]) ? fabs(y[i]) : fabs(s->y_new[i]);
        for (j = 0; j < DOP853_STAGES; j++) {
            a5 += dop853_e5[j] * s->k[j * d + i];
            a3 += (dop853_b[j] - dop853_bhh[j]) * s->k[j * d + i];
        }
        scale = s->atol + big * s->rtol;
        r5 = a5 / scale;
        r3 = a3 / scale;
        e5 += r5 * r5;
        e3 += r3 * r3;
    }
    denom = e5 + 0.01 * e3;
    *err = denom == 0.0 ? 0.0 : fabs(h) * e5 / sqrt(denom * (double)d);
    return DOP853_OK;
}

/* One accepted step towards t_end (not past it). */
static int advance(dop853_state *s, dop853_rhs rhs, void *context, double *t, double *y,
                   double t_end) {
    size_t d = s->dim;
    double exponent = -1.0 / (DOP853_ORDER + 1.0);
    int rejected_here = 0;
    if (!s->have_f) {
        if (rhs(context, *t, y, s->f) != 0) {
            return DOP853_RHS_FAILED;
        }
        s->evaluations++;
        s->have_f = 1;
    }
    memcpy(s->k, s->f, d * sizeof(double));
    if (s->h == 0.0) {
        int status = initial_step(s, rhs, context, *t, y, t_end, &s->h);
        if (status != DOP853_OK) {
            return status;
        }
    }
    for (;;) {
        double min_step = 10.0 * (fabs(*t) * DBL_EPSILON > DBL_MIN ? fabs(*t) * DBL_EPSILON
                                                                    : DBL_MIN);
        double h = s->h, t_new = *t + h, err, factor;
        int status;
        if (s->h < min_step) {
            return DOP853_STEP_TOO_SMALL;
        }
        if (t_new >= t_end) {
            t_new = t_end;
            h = t_end - *t;
        }
        status = trial(s, rhs, context, *t, y, h, &err);
        if (status == DOP853_RHS_FAILED) {
            /* A failed evaluation inside the step (a singular mass matrix, a NaN) may be the
             * step's fault: shrink it, and report only when it cannot shrink further. */
            if (h > 1e3 * min_step) {
                s->h = h * DOP853_MIN_FACTOR;
                s->rejected++;
                rejected_here = 1;
                continue;
            }
            return status;
        }
        if (err <= 1.0) {
            factor = err == 0.0 ? DOP853_MAX_FACTOR : DOP853_SAFETY * pow(err, exponent);
            if (factor > DOP853_MAX_FACTOR) {
                factor = DOP853_MAX_FACTOR;
            }
            if (rejected_here && factor > 1.0) {
                factor = 1.0;
            }
            s->h = h * factor;
            memcpy(y, s->y_new, d * sizeof(double));
            memcpy(s->f, s->k + DOP853_STAGES * d, d * sizeof(double));
            *t = t_new;
            return DOP853_OK;
        }
        factor = DOP853_SAFETY * pow(err, exponent);
        s->h = h * (factor > DOP853_MIN_FACTOR ? factor : DOP853_MIN_FACTOR);
        s->rejected++;
        rejected_here = 1;
    }
}

int dop853_integrate(dop853_state *s, dop853_rhs rhs, void *context, double *t, double *y,
                     double t_end) {
    while (*t < t_end) {
        int status = advance(s, rhs, context, t, y, t_end);
        if (status != DOP853_OK) {
            return status;
        }
    }
    return DOP853_OK;
}
