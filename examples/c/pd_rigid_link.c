/* flexmor from C: user control laws as callbacks (include/flexmor.h, docs/api.md).
 *
 * Two runs side by side in one process, each with its own law and data: a continuous PD on
 * rigid_link_pd.nml, checked against the closed form of the loop it makes, and a sampled PID
 * (its integral is the law's one state) on rigid_link_pid.nml, whose integral action brings
 * the link back to zero where the PD leaves tau / kp.
 *
 * Usage: pd_rigid_link <folder of the .nml files> [result file of the PD run]
 * Exits non-zero on any error or failed check. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include "flexmor.h"

/* The gains of one law and a count of its calls: each run has its own through user_data. */
struct gains {
  double kp, ki, kd, period;
  long calls;
};

/* PD regulating the angle to 0: u = -kp y - kd y'. No states. */
static int pd_law(double t, int n_y, const double *y, const double *y_dot, int n_x,
                  const double *x, double *x_out, int n_u, double *u, void *user_data) {
  struct gains *g = user_data;
  (void)t; (void)x; (void)x_out;
  if (n_y != 1 || n_u != 1 || n_x != 0) return -1; /* not the scene this law is for */
  u[0] = -g->kp * y[0] - g->kd * y_dot[0];
  g->calls++;
  return 0;
}

/* Sampled PID: u from the integral x before the sample, then x + T e (e = -y). */
static int pid_law(double t, int n_y, const double *y, const double *y_dot, int n_x,
                   const double *x, double *x_out, int n_u, double *u, void *user_data) {
  struct gains *g = user_data;
  (void)t;
  if (n_y != 1 || n_u != 1 || n_x != 1) return -1;
  u[0] = -g->kp * y[0] + g->ki * x[0] - g->kd * y_dot[0];
  x_out[0] = x[0] - g->period * y[0];
  g->calls++;
  return 0;
}

static int failures = 0;

static void check(int ok, const char *what, double value, double bound) {
  printf("  %s  %s: %.3e (bound %.1e)\n", ok ? "ok  " : "FAIL", what, value, bound);
  if (!ok) failures++;
}

static void require(int code, const char *what, const char *err) {
  if (code == 0) return;
  fprintf(stderr, "pd_rigid_link: %s: error %d: %s\n", what, code, err);
  exit(2);
}

/* The hinge angle at the output times, from the tip of the 1 m link. */
static double *tip_angle(flexmor_handle h, int *n, double **time) {
  char err[512];
  double *x, *y, *angle;
  int i;
  *n = flexmor_n_times(h);
  *time = malloc(*n * sizeof(double));
  x = malloc(*n * sizeof(double));
  y = malloc(*n * sizeof(double));
  angle = malloc(*n * sizeof(double));
  require(flexmor_node_position(h, "tip", *n, *time, x, y, err, sizeof err), "tip", err);
  for (i = 0; i < *n; i++) angle[i] = atan2(y[i], x[i]);
  free(x);
  free(y);
  return angle;
}

int main(int argc, char **argv) {
  /* The link's inertia about the hinge rho A L^3 / 3 and the disturbance torque. */
  const double J = 2700 * 1.0e-4 / 3, TAU = 0.05;
  struct gains pd = {2.0, 0.0, 0.5, 0.0, 0}, pid = {2.0, 1.0, 0.5, 1.0e-3, 0};
  char path[4096], err[512];
  flexmor_handle h_pd, h_pid;
  double *t, *t2, *angle, *angle2, worst = 0;
  int n, n2, i;
  if (argc < 2) {
    fprintf(stderr, "usage: pd_rigid_link <folder of the scene files> [result.h5]\n");
    return 2;
  }
  snprintf(path, sizeof path, "%s/rigid_link_pd.nml", argv[1]);
  h_pd = flexmor_open(path, err, sizeof err);
  require(h_pd == NULL, "open", err);
  snprintf(path, sizeof path, "%s/rigid_link_pid.nml", argv[1]);
  h_pid = flexmor_open(path, err, sizeof err);
  require(h_pid == NULL, "open", err);
  /* Misuse is an error with a message, never a crash. */
  check(flexmor_set_controller(h_pd, "nope", pd_law, &pd, err, sizeof err) == 1, "unknown label "
        "refused", 0, 0);
  printf("        (%s)\n", err);
  require(flexmor_set_controller(h_pd, "ext", pd_law, &pd, err, sizeof err), "set PD", err);
  require(flexmor_set_controller(h_pid, "ext", pid_law, &pid, err, sizeof err), "set PID", err);
  require(flexmor_execute(h_pd, err, sizeof err), "execute PD", err);
  require(flexmor_execute(h_pid, err, sizeof err), "execute PID", err);
  if (argc > 2) require(flexmor_write(h_pd, argv[2], err, sizeof err), "write", err);

  /* J y'' + kd y' + kp y = tau from rest, underdamped:
   * y = tau/kp (1 - exp(-z w t) (cos(wd t) + z w / wd sin(wd t))). */
  angle = tip_angle(h_pd, &n, &t);
  {
    double w = sqrt(pd.kp / J), z = pd.kd / (2 * sqrt(pd.kp * J)), wd = w * sqrt(1 - z * z);
    for (i = 0; i < n; i++) {
      double closed = TAU / pd.kp * (1 - exp(-z * w * t[i]) * (cos(wd * t[i]) +
                                                                z * w / wd * sin(wd * t[i])));
      worst = fmax(worst, fabs(angle[i] - closed));
    }
  }
  /* Observed 1.8e-10 rad (BDF, rtol 1e-9). */
  check(n == 1001 && worst < 1e-8, "PD: largest deviation from the closed form [rad]", worst,
        1e-8);
  angle2 = tip_angle(h_pid, &n2, &t2);
  /* The PD holds tau / kp = 0.025 rad; the PID's integral removes it, with the slow real pole
   * near -ki/kp = -0.5 /s: observed 1.06e-4 rad left at t = 10 s (0.4 % of tau / kp). */
  check(fabs(angle[n - 1] - TAU / pd.kp) < 1e-6, "PD: final offset from tau/kp [rad]",
        fabs(angle[n - 1] - TAU / pd.kp), 1e-6);
  check(fabs(angle2[n2 - 1]) < 1e-3, "PID: final angle [rad]", fabs(angle2[n2 - 1]), 1e-3);
  /* One call per sample for the sampled law, at t = 0, T, ..., 10 s - T (a sample at the end
   * would act after the run); many for the PD. */
  check(pid.calls == 10000, "PID: calls, one per sample", (double)pid.calls, 10000);
  check(pd.calls > 1000, "PD: calls (at trial states)", (double)pd.calls, 1000);
  flexmor_close(h_pd);
  flexmor_close(h_pid);
  free(t); free(t2); free(angle); free(angle2);
  if (failures) {
    printf("%d check(s) failed\n", failures);
    return 1;
  }
  printf("all checks passed\n");
  return 0;
}
