/* A user control law in a shared library, for &controller law = 'user', library, symbol,
 * params (docs/input.md; rigid_link_library.nml runs it):
 *
 *     gcc -shared -fPIC -O2 -o pid_law.so pid_law.c
 *     flexmor rigid_link_library.nml
 *
 * A PID on one measured output y holding it at a constant r:
 *
 *     u = kp e + ki x + kd e',   e = r - y,   e' = -y',   dx/dt = e,
 *
 * params = kp, ki, kd, r. With n_states = 1 the state x is the integral of e (the built-in
 * law = 'pid' with a constant reference, less its anti-windup); with n_states = 0 and ki = 0 it
 * is a PD. Continuous controllers only (period = 0): a sampled one would return the next x.
 *
 * The function has the signature of flexmor_control_law (include/flexmor.h), so a program can
 * give the same function with flexmor_set_controller and a pointer to its four doubles. */

/* The number of params the law reads: flexmor checks the scene's count against it. */
const int pid_law_n_params = 4;

int pid_law(double t, int n_y, const double *y, const double *y_dot, int n_x, const double *x,
            double *x_out, int n_u, double *u, void *user_data) {
  const double *p = user_data;
  double kp = p[0], ki = p[1], kd = p[2], r = p[3], e, e_dot;
  (void)t;
  /* Not the controller this law is for: a fatal status stops the run with an error. */
  if (n_y != 1 || n_u != 1 || n_x > 1 || (n_x == 0 && ki != 0)) return -1;
  e = r - y[0];
  e_dot = -y_dot[0];
  /* In the order of the built-in PID's sum: the same inputs give the same u. */
  u[0] = kp * e + ki * (n_x == 1 ? x[0] : 0) + kd * e_dot;
  if (n_x == 1) x_out[0] = e;
  return 0;
}
