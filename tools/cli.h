/*
 * cli.h — what the subcommands of the bspray tool share: exit codes, usage
 * errors, option parsing, and loading with messages. Only the tool prints.
 */
#ifndef BSPRAY_TOOLS_CLI_H
#define BSPRAY_TOOLS_CLI_H

#include "bspray/bspray.h"

#define EXIT_INPUT 1 /* bad input or failure at run time */
#define EXIT_USAGE 2 /* bad command line */

extern const char *prog;

/* The command line of one subcommand, walked by index. */
typedef struct args {
    int argc, i;
    char **argv;
    const char *usage;
} args;

/* Prints "bspray: " FMT (with ARG), the usage line and a hint; exits 2. */
void die_usage(const char *usage, const char *fmt, const char *arg) __attribute__((noreturn));
/* The value of option OPT (the next argument), or a usage error. */
const char *opt_value(args *a, const char *opt);
/* A whole number in [LO, HI] as the value of OPT, or a usage error. */
int parse_int(args *a, const char *opt, long lo, long hi);
int parse_on_off(args *a, const char *opt);
int is_help(const char *s);
/* A vector "x,y,z" as the value of OPT, or a usage error. */
bsp_vec3 parse_vec3(args *a, const char *opt);
/* --accel METHOD into OPTS->kind, or a usage error listing the methods. */
void parse_accel(args *a, bsp_build_options *opts);
/* Loads PATH (printing its warnings) or exits 1 with the message. */
bsp_scene *load_scene(const char *path);
/* Builds or exits 1 with the message. */
bsp_accel *build_accel(const bsp_scene *scene, const bsp_build_options *opts);
/* Seconds on a monotonic clock. */
double now_seconds(void);

/* The subcommands. */
int cmd_bench(int argc, char **argv);

#endif /* BSPRAY_TOOLS_CLI_H */
