/* viz.c — placeholder until the tree pictures land (being written now). */
#include <stdio.h>

#include "cli.h"

int cmd_viz(int argc, char **argv)
{
    (void)argc;
    (void)argv;
    fprintf(stderr, "%s viz: not built yet\n", prog);
    return EXIT_INPUT;
}
