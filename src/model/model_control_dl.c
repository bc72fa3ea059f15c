/* Shared libraries of user control laws (&controller library, symbol): dlopen and dlsym for
 * module model_control_c, with the platform's flags and dlerror()'s text for the messages. */
#include <dlfcn.h>
#include <stdio.h>

typedef void (*flexmor_dl_function_t)(void);

/* The reason of the failure that just happened into msg (NUL-terminated, cut to len - 1
 * characters). */
static void reason(const char *fallback, char *msg, int len) {
  const char *text = dlerror();
  if (len > 0) snprintf(msg, (size_t)len, "%s", text ? text : fallback);
}

/* RTLD_NOW: a function the library needs and cannot find fails here, with a message, instead of
 * ending the process at the law's first call. RTLD_LOCAL: its symbols do not take the place of
 * those of another law's library (two libraries may both have a `law`). Opening a file again
 * gives the same handle and counts up the loader's reference count. */
void *flexmor_dl_open(const char *path, char *msg, int len) {
  void *handle = dlopen(path, RTLD_NOW | RTLD_LOCAL);
  if (!handle) reason("unknown reason", msg, len);
  return handle;
}

/* The address of `symbol` in the library, NULL (with the reason) when it has none. */
void *flexmor_dl_data(void *handle, const char *symbol, char *msg, int len) {
  void *address;
  dlerror(); /* forget an earlier failure: only this lookup's counts */
  address = dlsym(handle, symbol);
  if (!address) reason("its address is NULL", msg, len);
  return address;
}

/* The same for a function. POSIX guarantees that dlsym's object pointer converts to a function
 * pointer; Fortran can only take it as such (c_funptr). */
flexmor_dl_function_t flexmor_dl_function(void *handle, const char *symbol, char *msg,
                                          int len) {
  return (flexmor_dl_function_t)flexmor_dl_data(handle, symbol, msg, len);
}
