/*
 * main.c — the test runner: runs every registered test (or those whose name
 * or file contains the one argument), each in a forked process of its own,
 * several at a time (--jobs), and ends with the plain line "N passed, N
 * failed" (plus ", N skipped" when some were skipped). Exit status 0 only if
 * none failed. A test that crashes, or whose process a sanitizer ends, is a
 * failure of that test alone.
 */
#include <errno.h>
#include <fcntl.h>
#include <setjmp.h>
#include <signal.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include "bspray/render.h"
#include "harness.h"
#include "render/plot.h"

#define MAX_TESTS 4096
#define MAX_JOBS 16
/* seconds a test may run before it is killed as hung (the slowest take about
 * 100 s under the sanitizers on a loaded 2-core machine) */
#define DEFAULT_TIMEOUT 900.0

typedef struct test_entry {
    const char *name, *file;
    test_fn fn;
    double secs; /* the last run's time (or the times file's, before the run) */
} test_entry;

static test_entry tests[MAX_TESTS];
static int ntests;
static int current_failed, current_skipped;
static jmp_buf current_jmp;

void harness_register(const char *name, const char *file, test_fn fn)
{
    if (ntests < MAX_TESTS)
        tests[ntests++] = (test_entry){name, file, fn, 0.0};
}

void harness_fail(const char *file, int line, const char *fmt, ...)
{
    va_list ap;
    fprintf(stderr, "  FAIL %s:%d: ", file, line);
    va_start(ap, fmt);
    vfprintf(stderr, fmt, ap);
    va_end(ap);
    fputc('\n', stderr);
    current_failed++;
}

void harness_abort_test(void)
{
    longjmp(current_jmp, 1);
}

void harness_skip(const char *fmt, ...)
{
    va_list ap;
    fprintf(stderr, "  SKIP: ");
    va_start(ap, fmt);
    vfprintf(stderr, fmt, ap);
    va_end(ap);
    fputc('\n', stderr);
    current_skipped = 1;
    longjmp(current_jmp, 1);
}

const char *harness_shared_dir(void)
{
    static int checked;
    static const char *dir;
    if (!checked) {
        checked = 1;
        const char *env = getenv("BSPRAY_SHARED");
        const char *cand = env && *env ? env : "../shared";
        struct stat st;
        char probe[4096];
        snprintf(probe, sizeof probe, "%s/scenes/spd/MANIFEST.md", cand);
        if (stat(probe, &st) == 0)
            dir = cand;
    }
    return dir;
}

const char *harness_cli(void)
{
    const char *env = getenv("BSPRAY_CLI");
    return env && *env ? env : "build/bspray";
}

/* Everything F has left, NUL-terminated, its length in *LEN. */
static char *read_stream(FILE *f, size_t *out_len)
{
    size_t cap = 1 << 16, len = 0, n;
    char *buf = malloc(cap);
    while (buf && (n = fread(buf + len, 1, cap - len - 1, f)) > 0) {
        len += n;
        if (cap - len < 4096) {
            char *nb = realloc(buf, cap * 2);
            if (!nb) {
                free(buf);
                return NULL;
            }
            buf = nb;
            cap *= 2;
        }
    }
    if (buf)
        buf[len] = 0;
    *out_len = len;
    return buf;
}

char *harness_read_all(FILE *f)
{
    size_t len;
    return read_stream(f, &len);
}

unsigned char *harness_read_file(const char *path, size_t *len)
{
    FILE *f = fopen(path, "rb");
    if (!f)
        return NULL;
    char *buf = read_stream(f, len);
    fclose(f);
    return (unsigned char *)buf;
}

void harness_tmp_path(char *buf, size_t size, const char *name)
{
    snprintf(buf, size, "%s/%s", harness_tmpdir(), name);
}

long harness_count_color(const struct bsp_image *img, int i)
{
    float rgb[3];
    plot_color(i, rgb);
    long n = 0;
    for (size_t p = 0; p < (size_t)img->width * (size_t)img->height; p++) {
        const float *px = img->rgb + 3 * p;
        n += fabsf(px[0] - rgb[0]) <= 1.5f / 255.0f && fabsf(px[1] - rgb[1]) <= 1.5f / 255.0f &&
             fabsf(px[2] - rgb[2]) <= 1.5f / 255.0f;
    }
    return n;
}

char *harness_run(const char *cmd, int *status)
{
    FILE *p = popen(cmd, "r");
    if (!p)
        return NULL;
    char *buf = harness_read_all(p);
    int st = pclose(p);
    *status = WIFEXITED(st) ? WEXITSTATUS(st) : -1;
    return buf;
}

/* The run's temporary directory (made by the runner) and, in a test's own
 * process, that test's subdirectory of it: tests running side by side never
 * share a file name. */
static char tmp_root[256], tmp_dir[320];
static pid_t tmp_root_owner;

const char *harness_tmpdir(void)
{
    if (!tmp_root[0]) {
        tmp_root_owner = getpid();
        snprintf(tmp_root, sizeof tmp_root, "/tmp/bspray-tests-%ld", (long)tmp_root_owner);
        mkdir(tmp_root, 0700);
    }
    if (!tmp_dir[0])
        snprintf(tmp_dir, sizeof tmp_dir, "%s", tmp_root);
    return tmp_dir;
}

/* In a forked test: its own subdirectory, named by the test's index. */
static void enter_test_tmpdir(int index)
{
    harness_tmpdir();
    snprintf(tmp_dir, sizeof tmp_dir, "%s/t%d", tmp_root, index);
    mkdir(tmp_dir, 0700);
}

/* Runs one test; returns 0 passed, 1 failed, 2 skipped. Kept apart from main
 * so that no local of main lives across the longjmp. */
static int run_one(test_fn fn)
{
    current_failed = 0;
    current_skipped = 0;
    if (setjmp(current_jmp) == 0)
        fn();
    return current_failed ? 1 : current_skipped ? 2 : 0;
}

/* At exit of the runner itself (not of a forked test, which inherits the
 * handler): the whole temporary tree. */
static void remove_tmpdir(void)
{
    if (!tmp_root[0] || getpid() != tmp_root_owner)
        return;
    char cmd[512];
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", tmp_root);
    if (system(cmd) != 0)
        fprintf(stderr, "warning: could not remove %s\n", tmp_root);
}

static int cmp_tests(const void *a, const void *b)
{
    const test_entry *x = a, *y = b;
    int c = strcmp(x->file, y->file);
    return c ? c : strcmp(x->name, y->name);
}

static double seconds_since(const struct timespec *t0)
{
    struct timespec t1;
    clock_gettime(CLOCK_MONOTONIC, &t1);
    return (double)(t1.tv_sec - t0->tv_sec) + 1e-9 * (double)(t1.tv_nsec - t0->tv_nsec);
}

typedef struct tally {
    int passed, failed, skipped;
    double total_secs; /* the tests' own times, summed */
    char failed_names[4096];
} tally;

static void record(tally *t, int i, int outcome, double secs)
{
    const char *verdict = "ok  ";
    if (outcome == 1) {
        t->failed++;
        verdict = "FAIL";
        size_t used = strlen(t->failed_names);
        snprintf(t->failed_names + used, sizeof t->failed_names - used, "%s%s",
                 used ? ", " : "", tests[i].name);
    } else if (outcome == 2) {
        t->skipped++;
        verdict = "skip";
    } else {
        t->passed++;
    }
    t->total_secs += secs;
    tests[i].secs = secs;
    fprintf(stderr, "%s %-48s %7.2fs  (%s)\n", verdict, tests[i].name, secs, tests[i].file);
}

/* The selected tests one after another in this process (--in-process: for a
 * debugger; a test then sees the state earlier tests left, e.g. a file-level
 * random generator). */
static void run_in_process(const int *order, int n, tally *t)
{
    for (int k = 0; k < n; k++) {
        struct timespec t0;
        clock_gettime(CLOCK_MONOTONIC, &t0);
        int outcome = run_one(tests[order[k]].fn);
        record(t, order[k], outcome, seconds_since(&t0));
    }
}

/* The signals that end a run: the runner catches them to end its tests
 * first (run_forked); a test's process keeps their defaults. */
static const int stop_signals[] = {SIGINT, SIGTERM, SIGHUP};

static void set_stop_handler(void (*handler)(int))
{
    for (size_t k = 0; k < sizeof stop_signals / sizeof *stop_signals; k++)
        signal(stop_signals[k], handler);
}

/* BUF: the file that holds test I's output until it ends. */
static void output_path(char *buf, size_t size, int i)
{
    snprintf(buf, size, "%s/out-%d.txt", tmp_root, i);
}

/* Test I in a process of its own, its output to the file OUT. */
static pid_t start_test(int i, const char *out)
{
    fflush(stdout);
    fflush(stderr);
    pid_t pid = fork();
    if (pid != 0)
        return pid;
    setpgid(0, 0);
    set_stop_handler(SIG_DFL);
    int in = open("/dev/null", O_RDONLY);
    if (in >= 0) {
        dup2(in, STDIN_FILENO);
        close(in);
    }
    int fd = open(out, O_WRONLY | O_CREAT | O_TRUNC, 0600);
    if (fd >= 0) {
        dup2(fd, STDOUT_FILENO);
        dup2(fd, STDERR_FILENO);
        close(fd);
    }
    enter_test_tmpdir(i);
    int outcome = run_one(tests[i].fn);
    fflush(stdout);
    fflush(stderr);
    /* exit, not _exit: LeakSanitizer checks this test's leaks at exit and
     * then exits with its own status, which the runner counts as a failure */
    exit(outcome);
}

/* The outcome of a forked test from its wait status; anything but an exit
 * with 0, 1 or 2 (a crash, a sanitizer's report) is a failure, said so. */
static int outcome_of(int status)
{
    if (WIFEXITED(status) && WEXITSTATUS(status) <= 2)
        return WEXITSTATUS(status);
    if (WIFSIGNALED(status))
        fprintf(stderr, "  FAIL: the test's process was killed by signal %d (%s)\n",
                WTERMSIG(status), strsignal(WTERMSIG(status)));
    else
        fprintf(stderr,
                "  FAIL: the test's process exited with status %d (a sanitizer's report?)\n",
                WIFEXITED(status) ? WEXITSTATUS(status) : -1);
    return 1;
}

static void copy_file_to_stderr(const char *path)
{
    size_t len;
    unsigned char *text = harness_read_file(path, &len);
    if (text) {
        fwrite(text, 1, len, stderr);
        free(text);
    }
    unlink(path);
}

/* The forked tests running now: each the leader of a process group of its
 * own, so that a hung test is ended with the commands it started, and an
 * interrupted run ends them all. */
typedef struct slot {
    pid_t pid;
    int test;
    int killed; /* for running over its time */
    struct timespec t0;
} slot;
static slot slots[MAX_JOBS];
static int nrunning;
static volatile sig_atomic_t interrupted; /* the signal that asked the run to end */

static void note_interrupt(int sig)
{
    interrupted = sig;
}

/* After an interrupt: ends the running tests' groups, reaps them, removes
 * the temporary tree, and dies of the same signal. */
static void end_interrupted_run(void)
{
    for (int k = 0; k < nrunning; k++)
        kill(-slots[k].pid, SIGKILL);
    for (int k = 0; k < nrunning; k++)
        waitpid(slots[k].pid, NULL, 0);
    nrunning = 0;
    remove_tmpdir();
    int sig = interrupted;
    signal(sig, SIG_DFL);
    raise(sig);
}

/* The selected tests in ORDER, each in a forked process, JOBS at a time. A
 * test's output is printed whole when it ends, then its verdict line. A test
 * still running after TIMEOUT seconds (0: no limit) is killed and fails. */
static void run_forked(const int *order, int n, int jobs, double timeout, tally *t)
{
    set_stop_handler(note_interrupt);
    int next = 0;
    char out[400];
    while (next < n || nrunning > 0) {
        if (interrupted)
            end_interrupted_run();
        while (nrunning < jobs && next < n) {
            int i = order[next++];
            output_path(out, sizeof out, i);
            slot *s = &slots[nrunning];
            clock_gettime(CLOCK_MONOTONIC, &s->t0);
            s->test = i;
            s->killed = 0;
            s->pid = start_test(i, out);
            if (s->pid < 0) {
                fprintf(stderr, "  FAIL: cannot fork for %s: %s\n", tests[i].name, strerror(errno));
                record(t, i, 1, 0.0);
                continue;
            }
            setpgid(s->pid, s->pid); /* also in the child: whichever runs first */
            nrunning++;
        }
        if (nrunning == 0)
            continue;
        int status;
        pid_t pid = waitpid(-1, &status, WNOHANG);
        if (pid == 0) { /* none has ended: any over its time? */
            for (int k = 0; k < nrunning; k++)
                if (timeout > 0 && !slots[k].killed && seconds_since(&slots[k].t0) > timeout) {
                    kill(-slots[k].pid, SIGKILL);
                    slots[k].killed = 1;
                    fprintf(stderr, "  FAIL: %s still running after %g s: killed (a hang?)\n",
                            tests[slots[k].test].name, timeout);
                }
            nanosleep(&(struct timespec){0, 10 * 1000 * 1000}, NULL);
            continue;
        }
        if (pid < 0) {
            if (errno == EINTR)
                continue;
            fprintf(stderr, "error: waitpid: %s\n", strerror(errno));
            exit(1);
        }
        int k = 0;
        while (k < nrunning && slots[k].pid != pid)
            k++;
        if (k == nrunning)
            continue; /* not a test of ours */
        slot done = slots[k];
        slots[k] = slots[nrunning - 1];
        nrunning--;
        kill(-done.pid, SIGKILL); /* anything the test left running in its group */
        output_path(out, sizeof out, done.test);
        copy_file_to_stderr(out);
        record(t, done.test, outcome_of(status), seconds_since(&done.t0));
    }
}

/* The previous full run's time of each test, from FILE ("seconds name" per
 * line), so that the longest start first and the run ends sooner. Tests not
 * in it (new ones) count as long. */
static void load_times(const char *path)
{
    for (int i = 0; i < ntests; i++)
        tests[i].secs = 1e9;
    FILE *f = fopen(path, "r");
    if (!f)
        return;
    char name[256];
    double secs;
    while (fscanf(f, "%lf %255s", &secs, name) == 2)
        for (int i = 0; i < ntests; i++)
            if (strcmp(tests[i].name, name) == 0)
                tests[i].secs = secs;
    fclose(f);
}

static void save_times(const char *path)
{
    FILE *f = fopen(path, "w");
    if (!f)
        return; /* only a hint for the next run's order */
    for (int i = 0; i < ntests; i++)
        fprintf(f, "%.3f %s\n", tests[i].secs, tests[i].name);
    fclose(f);
}

static int by_time_desc(const void *a, const void *b)
{
    double x = tests[*(const int *)a].secs, y = tests[*(const int *)b].secs;
    if (x != y)
        return x < y ? 1 : -1;
    return *(const int *)a - *(const int *)b;
}

static void usage(FILE *f)
{
    fprintf(f, "usage: bspray_tests [--jobs N] [--timeout S] [--in-process] [SUBSTRING]\n"
               "Runs every test (or those whose name or file contains SUBSTRING), each in a\n"
               "process of its own, N at a time (default: BSPRAY_TEST_JOBS, else the number of\n"
               "online processors, at most %d). A test still running after S seconds\n"
               "(default: BSPRAY_TEST_TIMEOUT, else %.0f; 0: no limit) is killed and fails.\n"
               "--in-process runs them one after another in this process (for a debugger;\n"
               "no timeout). Ends with \"N passed, N failed[, N skipped]\".\n",
            MAX_JOBS, DEFAULT_TIMEOUT);
}

/* N from TEXT when it is a whole number 1..MAX_JOBS, else 0. */
static int parse_jobs(const char *text)
{
    char *end;
    long v = text ? strtol(text, &end, 10) : 0;
    return text && *text && !*end && v >= 1 && v <= MAX_JOBS ? (int)v : 0;
}

int main(int argc, char **argv)
{
    const char *filter = NULL, *jobs_text = getenv("BSPRAY_TEST_JOBS");
    const char *timeout_text = getenv("BSPRAY_TEST_TIMEOUT");
    int in_process = 0;
    for (int a = 1; a < argc; a++) {
        if (strcmp(argv[a], "--jobs") == 0 || strcmp(argv[a], "-j") == 0) {
            if (++a == argc) {
                fprintf(stderr, "bspray_tests: %s needs a number\n", argv[a - 1]);
                return 2;
            }
            jobs_text = argv[a];
        } else if (strcmp(argv[a], "--timeout") == 0) {
            if (++a == argc) {
                fprintf(stderr, "bspray_tests: --timeout needs a number of seconds\n");
                return 2;
            }
            timeout_text = argv[a];
        } else if (strcmp(argv[a], "--in-process") == 0) {
            in_process = 1;
        } else if (strcmp(argv[a], "--help") == 0 || strcmp(argv[a], "-h") == 0) {
            usage(stdout);
            return 0;
        } else if (argv[a][0] == '-' || filter) {
            fprintf(stderr, "bspray_tests: unexpected argument '%s'\n", argv[a]);
            usage(stderr);
            return 2;
        } else {
            filter = argv[a];
        }
    }
    int jobs;
    if (jobs_text && *jobs_text) {
        jobs = parse_jobs(jobs_text);
        if (!jobs) {
            fprintf(stderr, "bspray_tests: the number of jobs must be 1..%d, not '%s'\n", MAX_JOBS,
                    jobs_text);
            return 2;
        }
    } else {
        long cpus = sysconf(_SC_NPROCESSORS_ONLN);
        jobs = cpus < 1 ? 1 : cpus > MAX_JOBS ? MAX_JOBS : (int)cpus;
    }

    double timeout = DEFAULT_TIMEOUT;
    if (timeout_text && *timeout_text) {
        char *end;
        timeout = strtod(timeout_text, &end);
        if (*end || !(timeout >= 0.0 && timeout < 1e9)) {
            fprintf(stderr,
                    "bspray_tests: the timeout must be a number of seconds >= 0, not '%s'\n",
                    timeout_text);
            return 2;
        }
    }

    harness_tmpdir();
    atexit(remove_tmpdir);
    qsort(tests, (size_t)ntests, sizeof tests[0], cmp_tests);
    /* the times file beside this program */
    char times_path[4096];
    const char *slash = strrchr(argv[0], '/');
    snprintf(times_path, sizeof times_path, "%.*stest-times.txt",
             slash ? (int)(slash - argv[0] + 1) : 0, argv[0]);
    load_times(times_path);

    static int order[MAX_TESTS];
    int n = 0;
    for (int i = 0; i < ntests; i++)
        if (!filter || strstr(tests[i].name, filter) || strstr(tests[i].file, filter))
            order[n++] = i;
    tally t = {0};
    struct timespec t0;
    clock_gettime(CLOCK_MONOTONIC, &t0);
    if (in_process) {
        run_in_process(order, n, &t);
    } else {
        qsort(order, (size_t)n, sizeof order[0], by_time_desc);
        fprintf(stderr, "%d tests, %d at a time, each in a process of its own\n", n, jobs);
        run_forked(order, n, jobs, timeout, &t);
    }
    if (!filter)
        save_times(times_path);
    fprintf(stderr, "the tests took %.1fs in all, %.1fs from start to end\n", t.total_secs,
            seconds_since(&t0));
    if (t.failed)
        fprintf(stderr, "failed: %s\n", t.failed_names);
    fflush(stderr);
    if (t.skipped)
        printf("%d passed, %d failed, %d skipped\n", t.passed, t.failed, t.skipped);
    else
        printf("%d passed, %d failed\n", t.passed, t.failed);
    return t.failed ? 1 : 0;
}
