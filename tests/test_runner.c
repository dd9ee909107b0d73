/*
 * test_runner.c — the test runner itself (tests/main.c): a test that
 * crashes or hangs fails alone, with the reason said, and the run goes on.
 * The runner is run again on fixtures that exist only when
 * BSPRAY_TEST_RUNNER_FIXTURES is set (they are not tests of their own).
 */
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <unistd.h>

#include "harness.h"

/* abort, not a SIGSEGV: AddressSanitizer catches the latter and exits */
static void fixture_crash(void)
{
    printf("fixture_crash: about to crash\n");
    fflush(stdout);
    abort();
}

static void fixture_hang(void)
{
    for (;;)
        pause();
}

static void fixture_pass(void)
{
    printf("fixture_pass: ran\n");
}

__attribute__((constructor)) static void register_fixtures(void)
{
    if (!getenv("BSPRAY_TEST_RUNNER_FIXTURES"))
        return;
    harness_register("fixture_crash", __FILE__, fixture_crash);
    harness_register("fixture_hang", __FILE__, fixture_hang);
    harness_register("fixture_pass", __FILE__, fixture_pass);
}

/* This program's own path (Linux). */
static const char *self_path(void)
{
    static char path[4096];
    ssize_t n = readlink("/proc/self/exe", path, sizeof path - 1);
    if (n <= 0)
        harness_skip("no /proc/self/exe to run the runner again");
    path[n] = 0;
    return path;
}

TEST(runner_isolates_crashes_and_hangs)
{
    char cmd[8192];
    snprintf(cmd, sizeof cmd,
             "BSPRAY_TEST_RUNNER_FIXTURES=1 '%s' --jobs 2 --timeout 1 fixture_ 2>&1", self_path());
    /* the crash and the hang fail with their reasons, the passing fixture
     * still runs and passes, and its output comes before its verdict */
    CHECK_RUN(cmd, 1, "fixture_crash: about to crash", "killed by signal 6",
              "fixture_hang still running after 1 s: killed",
              "fixture_pass: ran\nok   fixture_pass",
              "failed: ", "1 passed, 2 failed");
    /* the same with the fixtures one after another */
    snprintf(cmd, sizeof cmd,
             "BSPRAY_TEST_RUNNER_FIXTURES=1 '%s' --jobs 1 --timeout 1 fixture_ 2>&1", self_path());
    CHECK_RUN(cmd, 1, "killed by signal 6", "still running after 1 s", "1 passed, 2 failed");
}

TEST(runner_refuses_bad_arguments)
{
    char cmd[8192];
    const char *bad[] = {"--jobs 0", "--jobs 17", "--jobs x", "--timeout -1", "--timeout abc",
                         "--bogus", "a b"};
    const char *want[] = {"must be 1..16", "must be 1..16", "must be 1..16", "timeout must be",
                          "timeout must be", "unexpected argument", "unexpected argument"};
    for (size_t k = 0; k < sizeof bad / sizeof *bad; k++) {
        snprintf(cmd, sizeof cmd, "'%s' %s 2>&1", self_path(), bad[k]);
        CHECK_RUN(cmd, 2, want[k]);
    }
}
