/*
 * progress.c — the CLI's terminal progress bar (see progress.h): label, a bar,
 * the percentage, elapsed time and an estimate of the time left, redrawn in
 * place with \r at most ~10 times a second, only on a terminal.
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "util/progress.h"

#define PROGRESS_BAR_WIDTH 20
#define PROGRESS_LABEL_MAX 64
#define PROGRESS_MIN_INTERVAL 0.1 /* seconds between redraws */

struct progress_bar {
    FILE *out;
    int enabled;
    int drawn;    /* something has been drawn on the current line */
    int prev_len; /* length of the last line drawn, to blank leftovers */
    double start; /* CLOCK_MONOTONIC seconds */
    double last_draw;
    double fraction;
    char label[PROGRESS_LABEL_MAX];
};

static double now_seconds(void)
{
    struct timespec ts;
    if (clock_gettime(CLOCK_MONOTONIC, &ts) != 0)
        return 0.0;
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* "1.2s", "3m07s", "2h05m"; "?" when not finite or absurd. */
static void format_duration(char *buf, size_t size, double s)
{
    if (!(s >= 0.0))
        s = 0.0;
    if (!(s < 1e7)) {
        snprintf(buf, size, "?");
    } else if (s < 60.0) {
        snprintf(buf, size, "%.1fs", s);
    } else if (s < 3600.0) {
        long t = (long)s;
        snprintf(buf, size, "%ldm%02lds", t / 60, t % 60);
    } else {
        long t = (long)(s / 60.0);
        snprintf(buf, size, "%ldh%02ldm", t / 60, t % 60);
    }
}

static void draw(progress_bar *p, double now, int final)
{
    double f = final ? 1.0 : p->fraction;
    double elapsed = now - p->start;
    if (elapsed < 0.0)
        elapsed = 0.0;
    int filled = (int)(f * PROGRESS_BAR_WIDTH);
    int percent = (int)(f * 100.0);
    if (filled > PROGRESS_BAR_WIDTH)
        filled = PROGRESS_BAR_WIDTH;
    if (percent > 100)
        percent = 100;

    char bar[PROGRESS_BAR_WIDTH + 1];
    memset(bar, '#', (size_t)filled);
    memset(bar + filled, ' ', (size_t)(PROGRESS_BAR_WIDTH - filled));
    bar[PROGRESS_BAR_WIDTH] = '\0';

    char el[32], eta[32];
    format_duration(el, sizeof el, elapsed);
    char line[PROGRESS_LABEL_MAX + 128];
    int len;
    if (final || f <= 0.0) {
        len = snprintf(line, sizeof line, "%s%s[%s] %3d%%  %s", p->label, p->label[0] ? " " : "",
                       bar, percent, el);
    } else {
        format_duration(eta, sizeof eta, elapsed * (1.0 - f) / f);
        len = snprintf(line, sizeof line, "%s%s[%s] %3d%%  %s, ~%s left", p->label,
                       p->label[0] ? " " : "", bar, percent, el, eta);
    }
    if (len < 0)
        return;
    if (len >= (int)sizeof line)
        len = (int)sizeof line - 1;

    fputc('\r', p->out);
    fputs(line, p->out);
    for (int i = len; i < p->prev_len; i++) /* blank what a longer line left */
        fputc(' ', p->out);
    if (final)
        fputc('\n', p->out);
    fflush(p->out);
    p->prev_len = len;
    p->drawn = !final;
    p->last_draw = now;
}

progress_bar *progress_create(FILE *out, const char *label)
{
    progress_bar *p = calloc(1, sizeof *p);
    if (!p)
        return NULL;
    p->out = out;
    p->enabled = out && isatty(fileno(out)) && !getenv("BSPRAY_NO_PROGRESS");
    p->start = now_seconds();
    if (label)
        snprintf(p->label, sizeof p->label, "%s", label);
    return p;
}

int progress_enabled(const progress_bar *p)
{
    return p && p->enabled;
}

void progress_update(progress_bar *p, double fraction)
{
    if (!p || !p->enabled)
        return;
    if (!(fraction >= 0.0)) /* negative or NaN */
        fraction = 0.0;
    if (fraction > 1.0)
        fraction = 1.0;
    p->fraction = fraction;
    double now = now_seconds();
    if (p->drawn && now - p->last_draw < PROGRESS_MIN_INTERVAL)
        return;
    draw(p, now, 0);
}

void progress_finish(progress_bar *p)
{
    if (!p)
        return;
    if (p->enabled)
        draw(p, now_seconds(), 1);
    free(p);
}
