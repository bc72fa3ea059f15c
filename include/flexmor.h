/* flexmor: the C interface of the library (docs/api.md). Link with the flexmor library and the
 * Fortran runtime (CMake: find_package(flexmor) and target_link_libraries(app PRIVATE
 * flexmor::flexmor), which does both).
 *
 * A run is an opaque handle: open it on a scene file, give the scene's user control laws
 * (&controller law = 'user' without a `library`, docs/input.md), execute, write the result
 * file, close. Every
 * handle owns its run and its callbacks: several handles may live side by side in one process
 * (not used from two threads at once).
 *
 * Functions that can fail return 0 on success or an error code (1 bad input, 2 inconsistent
 * model, 3 numerical failure, 4 file system or HDF5, 5 internal) and write the one-line
 * message, NUL-terminated and cut to errlen - 1 characters, into errbuf ("" on success). */
#ifndef FLEXMOR_H
#define FLEXMOR_H

#ifdef __cplusplus
extern "C" {
#endif

typedef void *flexmor_handle;

/* A user control law. At time t it gets the measured outputs y[n_y] and their rates
 * y_dot[n_y] (in the order of the &controller's `measure` list) and its states x[n_x]
 * (n_states), and fills the actuator inputs u[n_u] (order of `actuator`; limited by the run to
 * [u_min, u_max]) and x_out[n_x]: dx/dt for a continuous controller (period = 0: x is
 * integrated with the model), the states after the sample for a sampled one (period > 0: it
 * is called once per sample and u is held until the next). A continuous law is called at the
 * integrator's trial states, so it keeps its memory in x, not in user_data.
 * Return 0 on success, > 0 for a recoverable failure (the integrator retries a shorter step),
 * < 0 for a fatal one (the run stops with an error naming the controller).
 *
 * A scene can name such a function itself (&controller library = 'laws.so', symbol = 'law',
 * params = ..., docs/input.md): then user_data points to the params as doubles (NULL without;
 * a copy for the call, not to be kept), and the library may declare their count,
 * `const int law_n_params = N;`, which the scene's must match. So one function serves a
 * program and a scene. */
typedef int (*flexmor_control_law)(double t, int n_y, const double *y, const double *y_dot,
                                   int n_x, const double *x, double *x_out, int n_u,
                                   double *u, void *user_data);

/* Read the scene file `path` and build the model. Returns the handle, or NULL with the error
 * in errbuf. */
flexmor_handle flexmor_open(const char *path, char *errbuf, int errlen);

/* Give the &controller `label` (law = 'user') its law, between flexmor_open and
 * flexmor_execute; user_data is passed to every call (it must stay valid until the run is
 * executed). Setting a label again replaces its law, as it replaces a law of the scene's
 * `library`. */
int flexmor_set_controller(flexmor_handle handle, const char *label,
                           flexmor_control_law callback, void *user_data, char *errbuf,
                           int errlen);

/* Run the scene's analyses. A &dynamic analysis with a user controller whose law was not set
 * is an input error. */
int flexmor_execute(flexmor_handle handle, char *errbuf, int errlen);

/* Write the HDF5 result file (docs/output.md) to `path`. */
int flexmor_write(flexmor_handle handle, const char *path, char *errbuf, int errlen);

/* The number of output times of the dynamic analysis (0 without one or before execute). */
int flexmor_n_times(flexmor_handle handle);

/* The output times and the x and y positions [m] of node `label` at them, n =
 * flexmor_n_times(handle) values each. */
int flexmor_node_position(flexmor_handle handle, const char *label, int n, double *time,
                          double *x, double *y, char *errbuf, int errlen);

/* Free the run (NULL is allowed). */
void flexmor_close(flexmor_handle handle);

#ifdef __cplusplus
}
#endif
#endif /* FLEXMOR_H */
