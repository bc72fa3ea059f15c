/* Small POSIX file-system helpers for flexmor, called from Fortran through bind(C) (module io_fs):
 * rename, unlink, fsync, probing an output path, and the interrupt guard of the result file.
 * Functions returning int return 0 on success or the errno value of the failure. */
#define _POSIX_C_SOURCE 200809L
#include <errno.h>
#include <fcntl.h>
#include <signal.h>
#include <libgen.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

/* flexmor_probe_output: the path exists and is neither a folder nor a regular file (not an
 * errno value: those are positive). */
#define FLEXMOR_NOT_REGULAR (-1)

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

/* mkdir(2) with mode 0777 (less the umask); a folder that exists already is not an error,
 * anything else there is (ENOTDIR). */
int flexmor_mkdir(const char *path)
{
    if (mkdir(path, 0777) == 0) return 0;
    int rc = errno;
    struct stat st;
    if (rc == EEXIST) return stat(path, &st) == 0 && S_ISDIR(st.st_mode) ? 0 : ENOTDIR;
    return rc;
}

/* Text of an errno value, NUL-terminated, truncated to `len` bytes. */
void flexmor_strerror(int code, char *buf, size_t len)
{
    if (len == 0) return;
    snprintf(buf, len, "%s", strerror(code));
}

/* Can `path` become a result file? 0, or EISDIR when it is a folder, or the errno of creating
 * the temporary file `tmp` next to it (ENOENT: the folder does not exist; EACCES, EROFS, ...).
 * `folder_missing` tells whether the folder of `path` is absent. The probe file is removed again; a leftover `tmp` of an earlier run is truncated, as the
 * writer would do anyway. */
/* 1 when both paths name one existing file (same device and inode, whatever the spelling). */
int flexmor_same_file(const char *a, const char *b)
{
    struct stat sa, sb;
    if (stat(a, &sa) != 0 || stat(b, &sb) != 0) return 0;
    return sa.st_dev == sb.st_dev && sa.st_ino == sb.st_ino;
}

int flexmor_probe_output(const char *path, const char *tmp, int *folder_missing)
{
    struct stat st;
    *folder_missing = 0;
    if (stat(path, &st) == 0 && S_ISDIR(st.st_mode)) return EISDIR;
    /* The result is renamed onto `path`: a device, pipe or socket there (-o /dev/null, run
     * as root) would be replaced by a regular file, not written to. */
    if (stat(path, &st) == 0 && !S_ISREG(st.st_mode)) return FLEXMOR_NOT_REGULAR;
    int fd = open(tmp, O_WRONLY | O_CREAT | O_TRUNC, 0666);
    if (fd < 0) {
        int rc = errno;
        char *copy = strdup(path);
        if (copy != NULL) {
            *folder_missing = stat(dirname(copy), &st) != 0 || !S_ISDIR(st.st_mode);
            free(copy);
        }
        return rc;
    }
    (void)close(fd);
    (void)unlink(tmp);
    return 0;
}

/* ---- Interrupts: SIGINT and SIGTERM leave no result file behind -----------------------------
 * Signals are process-wide, so this state is too (the one place flexmor keeps any): the paths
 * of the result file being written. The handler only calls async-signal-safe functions
 * (unlink, write, _exit). */
static char guard_tmp[4096];
static char guard_final[4096];
static volatile sig_atomic_t guard_final_ours = 0;

static void put_text(const char *s)
{
    ssize_t ignored = write(STDERR_FILENO, s, strlen(s));
    (void)ignored;
}

static char guard_msg_int[1024];
static char guard_msg_term[1024];

static void on_interrupt(int sig)
{
    if (guard_tmp[0] != '\0') (void)unlink(guard_tmp);
    if (guard_final_ours && guard_final[0] != '\0') (void)unlink(guard_final);
    put_text(sig == SIGINT ? guard_msg_int : guard_msg_term);
    _exit(128 + sig);
}

/* Install the handler for SIGINT and SIGTERM (the executables call it once at start); it prints
 * the line given for that signal (may be empty) and exits with 128 + the signal number. It is
 * installed even when the shell started us with SIGINT ignored (a background job): an
 * interrupt must never leave half a result behind. */
int flexmor_guard_install(const char *msg_int, const char *msg_term)
{
    struct sigaction sa;
    snprintf(guard_msg_int, sizeof guard_msg_int, "%s", msg_int);
    snprintf(guard_msg_term, sizeof guard_msg_term, "%s", msg_term);
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_interrupt;
    sigfillset(&sa.sa_mask);
    if (sigaction(SIGINT, &sa, NULL) != 0) return errno;
    if (sigaction(SIGTERM, &sa, NULL) != 0) return errno;
    return 0;
}

/* Block the two signals while the paths change, so the handler never sees half a path. */
static void guard_block(int how)
{
    sigset_t set;
    sigemptyset(&set);
    sigaddset(&set, SIGINT);
    sigaddset(&set, SIGTERM);
    (void)sigprocmask(how, &set, NULL);
}

/* From now on an interrupt deletes `tmp`; with `final_ours` also `final` (set just before the
 * rename makes it ours: an interrupt in the middle of committing leaves no file either). */
void flexmor_guard_set(const char *tmp, const char *final, int final_ours)
{
    guard_block(SIG_BLOCK);
    snprintf(guard_tmp, sizeof guard_tmp, "%s", tmp);
    snprintf(guard_final, sizeof guard_final, "%s", final);
    guard_final_ours = final_ours;
    guard_block(SIG_UNBLOCK);
}

/* Nothing to delete on an interrupt any more (the file is committed for good, or aborted). */
void flexmor_guard_clear(void)
{
    guard_block(SIG_BLOCK);
    guard_tmp[0] = '\0';
    guard_final[0] = '\0';
    guard_final_ours = 0;
    guard_block(SIG_UNBLOCK);
}
