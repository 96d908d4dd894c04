/* fail_write: an LD_PRELOAD library that makes writes into one folder fail as on a full disk.
 *
 * Counted calls are those on a file descriptor that refers to a regular file whose path
 * (readlink of /proc/self/fd/N) is FLOWIRE_FAIL_DIR or lies under it, and whose operation
 * class is listed in FLOWIRE_FAIL_OPS (comma separated; default "write"):
 *   write  write, writev, pwrite, pwrite64, pwritev, pwritev2 (on files opened for writing)
 *   sync   fsync, fdatasync
 *   close  close and fclose of files opened for writing (the file is still closed: the
 *          error is the deferred one a full disk or a network file system reports there)
 * Files whose name (last path component) is listed in FLOWIRE_FAIL_IGNORE (comma separated)
 * are never counted.
 *
 * FLOWIRE_FAIL_AT=N      the N-th counted call (1-based) and every later one fail with ENOSPC
 *                        (a full disk stays full); unset or 0: nothing fails
 * FLOWIRE_FAIL_COUNT=F   at exit, append "<pid> <counted calls>\n" to F
 * FLOWIRE_FAIL_TRACE=F   append "<n> <op> <ok|fail> <path>\n" to F for every counted call
 * FLOWIRE_FAIL_DELAY_US=D  every counted call first sleeps D microseconds (a slow disk: a
 *                        signal then often arrives while a file is being written)
 *
 * Counters are per process (a child started with exec counts from zero). F must not lie
 * under FLOWIRE_FAIL_DIR. */
#define _GNU_SOURCE
#include <dlfcn.h>
#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/types.h>
#include <sys/uio.h>
#include <time.h>
#include <unistd.h>

enum { OP_WRITE = 1, OP_SYNC = 2, OP_CLOSE = 4 };

typedef ssize_t (*write_fn)(int, const void*, size_t);
typedef ssize_t (*writev_fn)(int, const struct iovec*, int);
typedef ssize_t (*pwrite_fn)(int, const void*, size_t, off_t);
typedef ssize_t (*pwrite64_fn)(int, const void*, size_t, off64_t);
typedef ssize_t (*pwritev_fn)(int, const struct iovec*, int, off_t);
typedef ssize_t (*pwritev2_fn)(int, const struct iovec*, int, off_t, int);
typedef int (*fd_fn)(int);
typedef int (*fclose_fn)(FILE*);

static write_fn real_write;
static writev_fn real_writev;
static pwrite_fn real_pwrite;
static pwrite64_fn real_pwrite64;
static pwritev_fn real_pwritev;
static pwritev2_fn real_pwritev2;
static fd_fn real_fsync;
static fd_fn real_fdatasync;
static fd_fn real_close;
static fclose_fn real_fclose;

static char g_dir[PATH_MAX];
static size_t g_dir_len;
static char g_ignore[1024];
static int g_ops = OP_WRITE;
static long g_fail_at;
static long g_delay_us;
static char g_count_path[PATH_MAX];
static int g_trace_fd = -1;
static atomic_long g_counter;
static atomic_int g_ready;

static void resolve(void) {
  real_write = (write_fn)dlsym(RTLD_NEXT, "write");
  real_writev = (writev_fn)dlsym(RTLD_NEXT, "writev");
  real_pwrite = (pwrite_fn)dlsym(RTLD_NEXT, "pwrite");
  real_pwrite64 = (pwrite64_fn)dlsym(RTLD_NEXT, "pwrite64");
  real_pwritev = (pwritev_fn)dlsym(RTLD_NEXT, "pwritev");
  real_pwritev2 = (pwritev2_fn)dlsym(RTLD_NEXT, "pwritev2");
  real_fsync = (fd_fn)dlsym(RTLD_NEXT, "fsync");
  real_fdatasync = (fd_fn)dlsym(RTLD_NEXT, "fdatasync");
  real_close = (fd_fn)dlsym(RTLD_NEXT, "close");
  real_fclose = (fclose_fn)dlsym(RTLD_NEXT, "fclose");
}

static void copy_env(const char* name, char* dst, size_t size) {
  const char* v = getenv(name);
  dst[0] = '\0';
  if (v && strlen(v) < size) strcpy(dst, v);
}

static int parse_ops(const char* v) {
  if (!v || !*v) return OP_WRITE;
  int ops = 0;
  if (strstr(v, "write")) ops |= OP_WRITE;
  if (strstr(v, "sync")) ops |= OP_SYNC;
  if (strstr(v, "close")) ops |= OP_CLOSE;
  return ops;
}

__attribute__((constructor)) static void fail_write_init(void) {
  resolve();
  copy_env("FLOWIRE_FAIL_DIR", g_dir, sizeof g_dir);
  g_dir_len = strlen(g_dir);
  while (g_dir_len > 1 && g_dir[g_dir_len - 1] == '/') g_dir[--g_dir_len] = '\0';
  copy_env("FLOWIRE_FAIL_IGNORE", g_ignore, sizeof g_ignore);
  copy_env("FLOWIRE_FAIL_COUNT", g_count_path, sizeof g_count_path);
  g_ops = parse_ops(getenv("FLOWIRE_FAIL_OPS"));
  const char* at = getenv("FLOWIRE_FAIL_AT");
  g_fail_at = at ? strtol(at, NULL, 10) : 0;
  const char* delay = getenv("FLOWIRE_FAIL_DELAY_US");
  g_delay_us = delay ? strtol(delay, NULL, 10) : 0;
  const char* trace = getenv("FLOWIRE_FAIL_TRACE");
  if (trace && *trace) g_trace_fd = open(trace, O_WRONLY | O_CREAT | O_APPEND | O_CLOEXEC, 0644);
  atomic_store(&g_ready, 1);
}

static void put(int fd, const char* s, size_t n) {
  while (n > 0) {
    const ssize_t w = real_write(fd, s, n);
    if (w <= 0) return;
    s += w;
    n -= (size_t)w;
  }
}

__attribute__((destructor)) static void fail_write_fini(void) {
  if (!g_count_path[0] || !real_write) return;
  const int fd = open(g_count_path, O_WRONLY | O_CREAT | O_APPEND | O_CLOEXEC, 0644);
  if (fd < 0) return;
  char line[64];
  const int n = snprintf(line, sizeof line, "%ld %ld\n", (long)getpid(), atomic_load(&g_counter));
  if (n > 0) put(fd, line, (size_t)n);
  real_close(fd);
}

/* Whether `name` is one of the comma-separated names of FLOWIRE_FAIL_IGNORE. */
static int ignored(const char* name) {
  const size_t len = strlen(name);
  for (const char* p = g_ignore; *p;) {
    const char* end = strchr(p, ',');
    const size_t n = end ? (size_t)(end - p) : strlen(p);
    if (n == len && strncmp(p, name, n) == 0) return 1;
    if (!end) break;
    p = end + 1;
  }
  return 0;
}

/* Whether a call of class `op` on `fd` counts; its path is left in `path`. */
static int counted(int fd, int op, char* path, size_t size) {
  if (!atomic_load(&g_ready) || g_dir_len == 0 || !(g_ops & op) || fd < 0 || fd == g_trace_fd) return 0;
  struct stat st;
  if (fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) return 0;
  if (op != OP_SYNC) {
    const int flags = fcntl(fd, F_GETFL);
    if (flags < 0 || (flags & O_ACCMODE) == O_RDONLY) return 0;
  }
  char link[64];
  snprintf(link, sizeof link, "/proc/self/fd/%d", fd);
  const ssize_t n = readlink(link, path, size - 1);
  if (n <= 0) return 0;
  path[n] = '\0';
  if (strncmp(path, g_dir, g_dir_len) != 0 || (path[g_dir_len] != '/' && path[g_dir_len] != '\0')) return 0;
  const char* slash = strrchr(path, '/');
  if (g_ignore[0] && ignored(slash ? slash + 1 : path)) return 0;
  return 1;
}

/* Counts the call; nonzero if it is to fail. */
static int fails(int fd, int op, const char* opname) {
  const int saved_errno = errno;  // the checks below must not show through a call that succeeds
  char path[PATH_MAX];
  const int count = counted(fd, op, path, sizeof path);
  errno = saved_errno;
  if (!count) return 0;
  const long n = atomic_fetch_add(&g_counter, 1) + 1;
  const int fail = g_fail_at > 0 && n >= g_fail_at;
  if (g_trace_fd >= 0) {
    char line[PATH_MAX + 64];
    const int len = snprintf(line, sizeof line, "%ld %s %s %s\n", n, opname, fail ? "fail" : "ok", path);
    if (len > 0) put(g_trace_fd, line, (size_t)len < sizeof line ? (size_t)len : sizeof line - 1);
  }
  if (g_delay_us > 0) {
    const struct timespec ts = {g_delay_us / 1000000, (g_delay_us % 1000000) * 1000};
    nanosleep(&ts, NULL);  // a signal cuts it short: fine
  }
  errno = saved_errno;
  return fail;
}

#define FAIL_IF(fd, op, name)  \
  do {                         \
    if (fails(fd, op, name)) { \
      errno = ENOSPC;          \
      return -1;               \
    }                          \
  } while (0)

ssize_t write(int fd, const void* buf, size_t count) {
  if (!real_write) resolve();
  FAIL_IF(fd, OP_WRITE, "write");
  return real_write(fd, buf, count);
}

ssize_t writev(int fd, const struct iovec* iov, int iovcnt) {
  if (!real_writev) resolve();
  FAIL_IF(fd, OP_WRITE, "writev");
  return real_writev(fd, iov, iovcnt);
}

ssize_t pwrite(int fd, const void* buf, size_t count, off_t offset) {
  if (!real_pwrite) resolve();
  FAIL_IF(fd, OP_WRITE, "pwrite");
  return real_pwrite(fd, buf, count, offset);
}

ssize_t pwrite64(int fd, const void* buf, size_t count, off64_t offset) {
  if (!real_pwrite64) resolve();
  FAIL_IF(fd, OP_WRITE, "pwrite64");
  return real_pwrite64(fd, buf, count, offset);
}

ssize_t pwritev(int fd, const struct iovec* iov, int iovcnt, off_t offset) {
  if (!real_pwritev) resolve();
  FAIL_IF(fd, OP_WRITE, "pwritev");
  return real_pwritev(fd, iov, iovcnt, offset);
}

ssize_t pwritev2(int fd, const struct iovec* iov, int iovcnt, off_t offset, int flags) {
  if (!real_pwritev2) resolve();
  FAIL_IF(fd, OP_WRITE, "pwritev2");
  return real_pwritev2(fd, iov, iovcnt, offset, flags);
}

int fsync(int fd) {
  if (!real_fsync) resolve();
  FAIL_IF(fd, OP_SYNC, "fsync");
  return real_fsync(fd);
}

int fdatasync(int fd) {
  if (!real_fdatasync) resolve();
  FAIL_IF(fd, OP_SYNC, "fdatasync");
  return real_fdatasync(fd);
}

int close(int fd) {
  if (!real_close) resolve();
  const int fail = fails(fd, OP_CLOSE, "close");
  const int r = real_close(fd);
  if (fail) {
    errno = ENOSPC;
    return -1;
  }
  return r;
}

int fclose(FILE* stream) {
  if (!real_fclose) resolve();
  const int fd = stream ? fileno(stream) : -1;
  const int fail = fd >= 0 && fails(fd, OP_CLOSE, "fclose");
  const int r = real_fclose(stream);
  if (fail) {
    errno = ENOSPC;
    return EOF;
  }
  return r;
}
