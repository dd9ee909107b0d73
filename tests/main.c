/*
 * main.c — the test runner: runs every registered test (or those whose name
 * contains argv[1]) and ends with the plain line "N passed, N failed" (plus
 * ", N skipped" when some were skipped). Exit status 0 only if none failed.
 */
#include <setjmp.h>
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

typedef struct test_entry {
    const char *name, *file;
    test_fn fn;
} test_entry;

static test_entry tests[MAX_TESTS];
static int ntests;
static int current_failed, current_skipped;
static jmp_buf current_jmp;

void harness_register(const char *name, const char *file, test_fn fn)
{
    if (ntests < MAX_TESTS)
        tests[ntests++] = (test_entry){name, file, fn};
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

const char *harness_tmpdir(void)
{
    static char dir[256];
    if (!dir[0]) {
        snprintf(dir, sizeof dir, "/tmp/bspray-tests-%ld", (long)getpid());
        mkdir(dir, 0700);
    }
    return dir;
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

static void remove_tmpdir(void)
{
    const char *dir = harness_tmpdir();
    char cmd[512];
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
    if (system(cmd) != 0)
        fprintf(stderr, "warning: could not remove %s\n", dir);
}

static int cmp_tests(const void *a, const void *b)
{
    const test_entry *x = a, *y = b;
    int c = strcmp(x->file, y->file);
    return c ? c : strcmp(x->name, y->name);
}

int main(int argc, char **argv)
{
    const char *filter = argc > 1 ? argv[1] : NULL;
    int passed = 0, failed = 0, skipped = 0;
    double total_secs = 0.0; /* the tests' own times, summed */
    harness_tmpdir();
    atexit(remove_tmpdir);
    qsort(tests, (size_t)ntests, sizeof tests[0], cmp_tests);
    for (int i = 0; i < ntests; i++) {
        if (filter && !strstr(tests[i].name, filter) && !strstr(tests[i].file, filter))
            continue;
        struct timespec t0, t1;
        clock_gettime(CLOCK_MONOTONIC, &t0);
        int outcome = run_one(tests[i].fn);
        clock_gettime(CLOCK_MONOTONIC, &t1);
        double secs = (double)(t1.tv_sec - t0.tv_sec) + 1e-9 * (double)(t1.tv_nsec - t0.tv_nsec);
        total_secs += secs;
        const char *verdict;
        if (outcome == 1) {
            failed++;
            verdict = "FAIL";
        } else if (outcome == 2) {
            skipped++;
            verdict = "skip";
        } else {
            passed++;
            verdict = "ok  ";
        }
        fprintf(stderr, "%s %-48s %7.2fs  (%s)\n", verdict, tests[i].name, secs, tests[i].file);
    }
    fprintf(stderr, "the tests took %.1fs in all\n", total_secs);
    fflush(stderr);
    if (skipped)
        printf("%d passed, %d failed, %d skipped\n", passed, failed, skipped);
    else
        printf("%d passed, %d failed\n", passed, failed);
    return failed ? 1 : 0;
}
