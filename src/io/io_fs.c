/* Small POSIX file-system helpers for flexmor, called from Fortran through bind(C) (module io_fs).
 * Every function returns 0 on success or the errno value of the failure. */
#define _POSIX_C_SOURCE 200809L
#include <errno.h>
#include <fcntl.h>
#include <libgen.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

/* fsync the folder holding `path` so a rename in it survives a crash (best effort). */
static void sync_parent_dir(const char *path)
{
    char *copy = strdup(path);
    if (copy == NULL) return;
    int fd = open(dirname(copy), O_RDONLY);
    if (fd >= 0) {
        (void)fsync(fd);
        (void)close(fd);
    }
    free(copy);
}

/* rename(2): atomically replaces `to` if it exists (same file system). */
int flexmor_rename(const char *from, const char *to)
{
    if (rename(from, to) != 0) return errno;
    sync_parent_dir(to);
    return 0;
}

/* unlink(2). */
int flexmor_unlink(const char *path)
{
    return unlink(path) == 0 ? 0 : errno;
}

/* Flush a file's data to stable storage (open + fsync + close). */
int flexmor_fsync_path(const char *path)
{
    int fd = open(path, O_RDONLY);
    if (fd < 0) return errno;
    int rc = fsync(fd) == 0 ? 0 : errno;
    if (close(fd) != 0 && rc == 0) rc = errno;
    return rc;
}

/* Text of an errno value, NUL-terminated, truncated to `len` bytes. */
void flexmor_strerror(int code, char *buf, size_t len)
{
    if (len == 0) return;
    snprintf(buf, len, "%s", strerror(code));
}
