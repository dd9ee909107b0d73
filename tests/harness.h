/*
 * harness.h — a tiny test harness. Each tests/test_*.c file defines tests with
 * TEST(name) { ... }; they register themselves before main (a constructor), so
 * adding a file is all it takes. CHECK* macros record a failure and go on;
 * REQUIRE* macros end the current test. The runner (tests/main.c) runs each
 * test in a forked process of its own, several at once, so a test starts
 * from the program's initial state, shares nothing with the others, and
 * writes its files under harness_tmpdir() (its own directory). It prints one
 * line per failed check and ends with "N passed, N failed[, N skipped]".
 */
#ifndef BSPRAY_TESTS_HARNESS_H
#define BSPRAY_TESTS_HARNESS_H

#include <math.h>
#include <setjmp.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef void (*test_fn)(void);

void harness_register(const char *name, const char *file, test_fn fn);
void harness_fail(const char *file, int line, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));
/* Marks the current test skipped (with a reason) and ends it. */
void harness_skip(const char *fmt, ...) __attribute__((format(printf, 1, 2), noreturn));
/* Ends the current test (after a failed REQUIRE). */
void harness_abort_test(void) __attribute__((noreturn));
/* Path of ../shared relative to the repository, or NULL when it is absent. */
const char *harness_shared_dir(void);
/* Path of the CLI binary under test (BSPRAY_CLI, default build/bspray). */
const char *harness_cli(void);

/* One xorshift64* step of the state *S (seeded by the test, so failures
 * reproduce): its 64-bit output, a uniform double in [0, 1) from its top 53
 * bits, and its top 32 bits. */
static inline unsigned long long harness_xorshift64star(unsigned long long *s)
{
    *s ^= *s >> 12;
    *s ^= *s << 25;
    *s ^= *s >> 27;
    return *s * 2685821657736338717ULL;
}
static inline double harness_rnd(unsigned long long *s)
{
    return (double)(harness_xorshift64star(s) >> 11) * (1.0 / 9007199254740992.0);
}
static inline uint32_t harness_rnd_u32(unsigned long long *s)
{
    return (uint32_t)(harness_xorshift64star(s) >> 32);
}
/* Whether BSPRAY_TEST_QUICK asks for less work (the sanitizer run). */
static inline int harness_quick(void)
{
    const char *q = getenv("BSPRAY_TEST_QUICK");
    return q && *q && *q != '0';
}
/* In quick mode, ends the test as skipped, saying WHY (the sanitizer run
 * leaves out a few checks of figures that do not depend on the build). */
static inline void harness_skip_in_quick_mode(const char *why)
{
    if (harness_quick())
        harness_skip("quick mode (BSPRAY_TEST_QUICK): %s", why);
}
/* Marsaglia's xorshift64 step (13, 7, 17) of the state *S, and a uniform
 * double in [0, 1) from it: the generator of the older tests, kept so that
 * their seeds give the same cases. */
static inline uint64_t harness_xorshift64(uint64_t *s)
{
    *s ^= *s << 13;
    *s ^= *s >> 7;
    *s ^= *s << 17;
    return *s;
}
static inline double harness_xorshift_unit(uint64_t *s)
{
    return (double)(harness_xorshift64(s) >> 11) * (1.0 / 9007199254740992.0);
}
/* A fresh temporary directory for this test (created on first use; the
 * runner removes the whole tree at the end). */
const char *harness_tmpdir(void);
/* Everything F has left, NUL-terminated (malloc'd), or NULL when out of
 * memory. */
char *harness_read_all(FILE *f);
/* The whole file PATH (malloc'd, NUL-terminated after its *LEN bytes), or
 * NULL when it cannot be opened or read. */
unsigned char *harness_read_file(const char *path, size_t *len);
/* BUF: the path of NAME in this test's temporary directory. */
void harness_tmp_path(char *buf, size_t size, const char *name);
/* Runs CMD through the shell; returns its standard output (malloc'd, NUL
 * terminated; NULL when it cannot run) and sets *STATUS to its exit status
 * (-1 when it did not exit normally). */
char *harness_run(const char *cmd, int *status);
struct bsp_image;
/* Pixels of IMG (read back from an 8-bit PNG) within 1.5/255 of colour I of
 * the charts' palette (plot_color). */
long harness_count_color(const struct bsp_image *img, int i);

#define TEST(name)                                                                          \
    static void name(void);                                                                 \
    __attribute__((constructor)) static void register_##name(void)                          \
    {                                                                                       \
        harness_register(#name, __FILE__, name);                                            \
    }                                                                                       \
    static void name(void)

#define CHECK(cond)                                                                         \
    do {                                                                                    \
        if (!(cond))                                                                        \
            harness_fail(__FILE__, __LINE__, "CHECK(%s)", #cond);                           \
    } while (0)

#define CHECK_MSG(cond, ...)                                                                \
    do {                                                                                    \
        if (!(cond))                                                                        \
            harness_fail(__FILE__, __LINE__, __VA_ARGS__);                                  \
    } while (0)

#define REQUIRE(cond)                                                                       \
    do {                                                                                    \
        if (!(cond)) {                                                                      \
            harness_fail(__FILE__, __LINE__, "REQUIRE(%s)", #cond);                         \
            harness_abort_test();                                                           \
        }                                                                                   \
    } while (0)

#define REQUIRE_MSG(cond, ...)                                                              \
    do {                                                                                    \
        if (!(cond)) {                                                                      \
            harness_fail(__FILE__, __LINE__, __VA_ARGS__);                                  \
            harness_abort_test();                                                           \
        }                                                                                   \
    } while (0)

#define CHECK_EQ_INT(a, b)                                                                  \
    do {                                                                                    \
        long long check_a_ = (long long)(a), check_b_ = (long long)(b);                     \
        if (check_a_ != check_b_)                                                           \
            harness_fail(__FILE__, __LINE__, "CHECK_EQ_INT(%s, %s): %lld != %lld", #a, #b,  \
                         check_a_, check_b_);                                               \
    } while (0)

#define CHECK_NEAR(a, b, tol)                                                               \
    do {                                                                                    \
        double check_a_ = (double)(a), check_b_ = (double)(b);                              \
        if (!(fabs(check_a_ - check_b_) <= (tol)))                                          \
            harness_fail(__FILE__, __LINE__, "CHECK_NEAR(%s, %s): %.17g vs %.17g", #a, #b,  \
                         check_a_, check_b_);                                               \
    } while (0)

#define CHECK_STR_CONTAINS(hay, needle)                                                     \
    do {                                                                                    \
        const char *check_h_ = (hay), *check_n_ = (needle);                                 \
        if (!check_h_ || !strstr(check_h_, check_n_))                                       \
            harness_fail(__FILE__, __LINE__, "'%s' does not contain '%s'",                  \
                         check_h_ ? check_h_ : "(null)", check_n_);                         \
    } while (0)

/* Runs CMD (harness_run) once and checks its exit status and that its
 * output contains NEEDLE and every further needle given (one run for all:
 * some commands take seconds). */
#define CHECK_RUN(cmd, want_status, ...)                                                    \
    do {                                                                                    \
        int check_st_;                                                                      \
        char *check_out_ = harness_run((cmd), &check_st_);                                  \
        REQUIRE(check_out_);                                                                \
        CHECK_EQ_INT(check_st_, (want_status));                                             \
        const char *const check_needles_[] = {__VA_ARGS__};                                 \
        for (size_t check_i_ = 0;                                                           \
             check_i_ < sizeof check_needles_ / sizeof *check_needles_; check_i_++)         \
            CHECK_STR_CONTAINS(check_out_, check_needles_[check_i_]);                       \
        free(check_out_);                                                                   \
    } while (0)

#endif /* BSPRAY_TESTS_HARNESS_H */
