/*
 * test_image.c — bsp_image: creation limits, PNG and PPM writing (quantization
 * of out-of-range, NaN and halfway values), PNG reading of RGB, RGBA, gray,
 * palette, 16-bit and interlaced files, I/O errors; and the progress bar
 * (silent off a terminal, drawing on a pseudo-terminal).
 */
#define _XOPEN_SOURCE 700 /* posix_openpt, grantpt, unlockpt, ptsname */

#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <poll.h>
#include <setjmp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include <png.h>

#include "bspray/render.h"
#include "harness.h"
#include "util/progress.h"

/* --- helpers ------------------------------------------------------------------ */

static int spit(const char *path, const void *data, size_t len)
{
    FILE *fp = fopen(path, "wb");
    if (!fp)
        return -1;
    int ok = fwrite(data, 1, len, fp) == len;
    return (fclose(fp) == 0 && ok) ? 0 : -1;
}

/* The byte a float is written as: clamp to [0,1], (int)(v*255 + 0.5), NaN -> 0. */
static int expected_byte(float v)
{
    if (isnan(v))
        return 0;
    double d = v < 0.0f ? 0.0 : v > 1.0f ? 1.0 : (double)v;
    return (int)(d * 255.0 + 0.5);
}

/* Writes a PNG directly with libpng. ROWS holds HEIGHT rows of packed samples. */
static int write_raw_png(const char *path, int width, int height, int color_type, int bit_depth,
                         int interlace, const png_color *palette, int npalette,
                         unsigned char *const *rows)
{
    FILE *fp = fopen(path, "wb");
    if (!fp)
        return -1;
    png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, NULL, NULL, NULL);
    png_infop info = png ? png_create_info_struct(png) : NULL;
    if (!png || !info) {
        png_destroy_write_struct(png ? &png : NULL, NULL);
        fclose(fp);
        return -1;
    }
    if (setjmp(png_jmpbuf(png))) {
        png_destroy_write_struct(&png, &info);
        fclose(fp);
        return -1;
    }
    png_init_io(png, fp);
    png_set_IHDR(png, info, (png_uint_32)width, (png_uint_32)height, bit_depth, color_type,
                 interlace, PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
    if (palette)
        png_set_PLTE(png, info, palette, npalette);
    png_write_info(png, info);
    png_write_image(png, (png_bytepp)rows);
    png_write_end(png, info);
    png_destroy_write_struct(&png, &info);
    return fclose(fp) == 0 ? 0 : -1;
}

/* Checks that IMG is W x H and its pixel (x, y) is RGB/255. */
static void check_pixel(const bsp_image *img, int x, int y, int r, int g, int b)
{
    const float *p = img->rgb + ((size_t)y * (size_t)img->width + (size_t)x) * 3;
    CHECK_MSG(fabs(p[0] - r / 255.0) < 1e-6 && fabs(p[1] - g / 255.0) < 1e-6 &&
                  fabs(p[2] - b / 255.0) < 1e-6,
              "pixel (%d,%d): got %.1f %.1f %.1f, want %d %d %d", x, y, p[0] * 255.0,
              p[1] * 255.0, p[2] * 255.0, r, g, b);
}

/* A test image whose samples cover the awkward values. */
static const float sample_values[] = {
    -1.0f, 0.0f, 2.0f, NAN, 0.5f, 1.0f, INFINITY, -INFINITY, 0.2f, 1.0f / 255.0f,
    0.5f / 255.0f, 0.49f / 255.0f, 254.5f / 255.0f, 0.999f, 1e-30f, -0.0f, 0.75f, 0.25f,
    0.1f, 0.9f, 0.33f, 0.66f, 1.5f, 0.001f,
};

static bsp_image *make_sample_image(int width, int height)
{
    bsp_image *img = bsp_image_create(width, height);
    if (!img)
        return NULL;
    size_t n = (size_t)width * (size_t)height * 3;
    size_t nv = sizeof sample_values / sizeof sample_values[0];
    for (size_t i = 0; i < n; i++)
        img->rgb[i] = sample_values[i % nv];
    return img;
}

/* --- creation ------------------------------------------------------------------- */

TEST(image_create_limits)
{
    CHECK(bsp_image_create(0, 5) == NULL);
    CHECK(bsp_image_create(5, 0) == NULL);
    CHECK(bsp_image_create(5, -1) == NULL);
    CHECK(bsp_image_create(-3, 4) == NULL);
    CHECK(bsp_image_create(1 << 20, 1 << 20) == NULL);
    CHECK(bsp_image_create(1 << 14, (1 << 14) + 1) == NULL); /* just over 2^28 */
    CHECK(bsp_image_create(0x7fffffff, 0x7fffffff) == NULL);
    CHECK(bsp_image_create(0x7fffffff, 1) == NULL);
    bsp_image *img = bsp_image_create(3, 2);
    REQUIRE(img != NULL);
    CHECK_EQ_INT(img->width, 3);
    CHECK_EQ_INT(img->height, 2);
    REQUIRE(img->rgb != NULL);
    for (int i = 0; i < 3 * 2 * 3; i++)
        CHECK(img->rgb[i] == 0.0f);
    bsp_image_destroy(img);
    bsp_image_destroy(NULL);
}

/* --- PNG --------------------------------------------------------------------------- */

TEST(image_png_roundtrip_quantization)
{
    char path[512];
    harness_tmp_path(path, sizeof path, "roundtrip.png");
    bsp_image *img = make_sample_image(4, 3);
    REQUIRE(img != NULL);
    bsp_error err = {0};
    CHECK_EQ_INT(bsp_image_write_png(img, path, &err), BSP_OK);

    bsp_image *back = NULL;
    bsp_status st = bsp_image_read_png(path, &back, &err);
    CHECK_MSG(st == BSP_OK, "read: %s", err.message);
    REQUIRE(back != NULL);
    CHECK_EQ_INT(back->width, 4);
    CHECK_EQ_INT(back->height, 3);
    for (int i = 0; i < 4 * 3 * 3; i++) {
        int want = expected_byte(img->rgb[i]);
        CHECK_MSG(fabs(back->rgb[i] * 255.0 - want) < 1e-3, "sample %d (%g): got %g, want %d",
                  i, (double)img->rgb[i], back->rgb[i] * 255.0, want);
    }
    /* Spot checks of the quantization rule itself. */
    CHECK_EQ_INT(expected_byte(0.5f), 128);
    CHECK_NEAR(back->rgb[0], 0.0, 0.0);           /* -1 */
    CHECK_NEAR(back->rgb[2], 1.0, 1e-7);          /* 2 */
    CHECK_NEAR(back->rgb[3], 0.0, 0.0);           /* NaN */
    CHECK_NEAR(back->rgb[4] * 255.0, 128.0, 1e-3); /* 0.5 */
    CHECK_NEAR(back->rgb[10] * 255.0, 1.0, 1e-3); /* 0.5/255 rounds up */
    CHECK_NEAR(back->rgb[11] * 255.0, 0.0, 1e-3); /* 0.49/255 rounds down */
    bsp_image_destroy(back);
    bsp_image_destroy(img);
}

TEST(image_png_orientation_and_size)
{
    char path[512];
    harness_tmp_path(path, sizeof path, "orient.png");
    bsp_image *img = bsp_image_create(5, 7);
    REQUIRE(img != NULL);
    for (int y = 0; y < 7; y++)
        for (int x = 0; x < 5; x++) {
            float *p = img->rgb + ((size_t)y * 5 + (size_t)x) * 3;
            p[0] = (float)x / 255.0f;
            p[1] = (float)y / 255.0f;
            p[2] = (float)(x + 10 * y) / 255.0f;
        }
    REQUIRE(bsp_image_write_png(img, path, NULL) == BSP_OK);
    bsp_image *back = NULL;
    REQUIRE(bsp_image_read_png(path, &back, NULL) == BSP_OK);
    CHECK_EQ_INT(back->width, 5);
    CHECK_EQ_INT(back->height, 7);
    for (int y = 0; y < 7; y++)
        for (int x = 0; x < 5; x++)
            check_pixel(back, x, y, x, y, x + 10 * y);
    bsp_image_destroy(back);
    bsp_image_destroy(img);

    /* The file is an 8-bit RGB, non-interlaced PNG: check the IHDR bytes. */
    size_t len = 0;
    unsigned char *data = harness_read_file(path, &len);
    REQUIRE(data != NULL);
    CHECK(len > 33);
    if (len > 33) {
        CHECK(png_sig_cmp(data, 0, 8) == 0);
        CHECK(memcmp(data + 12, "IHDR", 4) == 0);
        CHECK_EQ_INT(data[24], 8); /* bit depth */
        CHECK_EQ_INT(data[25], 2); /* colour type RGB */
        CHECK_EQ_INT(data[28], 0); /* no interlace */
    }
    free(data);
}

TEST(image_read_gray_png)
{
    char path[512];
    harness_tmp_path(path, sizeof path, "gray.png");
    unsigned char r0[3] = {0, 128, 255}, r1[3] = {7, 200, 1};
    unsigned char *rows[2] = {r0, r1};
    REQUIRE(write_raw_png(path, 3, 2, PNG_COLOR_TYPE_GRAY, 8, PNG_INTERLACE_NONE, NULL, 0,
                          rows) == 0);
    bsp_image *img = NULL;
    bsp_error err = {0};
    bsp_status st = bsp_image_read_png(path, &img, &err);
    CHECK_MSG(st == BSP_OK, "%s", err.message);
    REQUIRE(img != NULL);
    CHECK_EQ_INT(img->width, 3);
    CHECK_EQ_INT(img->height, 2);
    for (int x = 0; x < 3; x++) {
        check_pixel(img, x, 0, r0[x], r0[x], r0[x]);
        check_pixel(img, x, 1, r1[x], r1[x], r1[x]);
    }
    bsp_image_destroy(img);
}

TEST(image_read_rgba_png)
{
    char path[512];
    harness_tmp_path(path, sizeof path, "rgba.png");
    unsigned char r0[8] = {10, 20, 30, 255, 40, 50, 60, 0};
    unsigned char r1[8] = {255, 0, 1, 128, 9, 99, 199, 1};
    unsigned char *rows[2] = {r0, r1};
    REQUIRE(write_raw_png(path, 2, 2, PNG_COLOR_TYPE_RGB_ALPHA, 8, PNG_INTERLACE_NONE, NULL, 0,
                          rows) == 0);
    bsp_image *img = NULL;
    bsp_error err = {0};
    bsp_status st = bsp_image_read_png(path, &img, &err);
    CHECK_MSG(st == BSP_OK, "%s", err.message);
    REQUIRE(img != NULL);
    check_pixel(img, 0, 0, 10, 20, 30);
    check_pixel(img, 1, 0, 40, 50, 60); /* alpha is dropped, not composited */
    check_pixel(img, 0, 1, 255, 0, 1);
    check_pixel(img, 1, 1, 9, 99, 199);
    bsp_image_destroy(img);
}

TEST(image_read_palette_16bit_lowbit_interlaced_png)
{
    char path[512];
    bsp_image *img = NULL;
    bsp_error err = {0};

    /* Palette, 8 bits per index. */
    harness_tmp_path(path, sizeof path, "palette.png");
    png_color pal[3] = {{1, 2, 3}, {200, 100, 50}, {255, 255, 0}};
    unsigned char p0[3] = {0, 1, 2};
    unsigned char *prow[1] = {p0};
    REQUIRE(write_raw_png(path, 3, 1, PNG_COLOR_TYPE_PALETTE, 8, PNG_INTERLACE_NONE, pal, 3,
                          prow) == 0);
    CHECK_MSG(bsp_image_read_png(path, &img, &err) == BSP_OK, "%s", err.message);
    REQUIRE(img != NULL);
    check_pixel(img, 0, 0, 1, 2, 3);
    check_pixel(img, 1, 0, 200, 100, 50);
    check_pixel(img, 2, 0, 255, 255, 0);
    bsp_image_destroy(img);
    img = NULL;

    /* 16-bit RGB: the high byte is kept. */
    harness_tmp_path(path, sizeof path, "rgb16.png");
    unsigned char s0[12] = {0x12, 0x34, 0xff, 0xff, 0x00, 0x01, 0x80, 0x00, 0x7f, 0xff, 0x01, 0x00};
    unsigned char *srow[1] = {s0};
    REQUIRE(write_raw_png(path, 2, 1, PNG_COLOR_TYPE_RGB, 16, PNG_INTERLACE_NONE, NULL, 0,
                          srow) == 0);
    CHECK_MSG(bsp_image_read_png(path, &img, &err) == BSP_OK, "%s", err.message);
    REQUIRE(img != NULL);
    check_pixel(img, 0, 0, 0x12, 0xff, 0x00);
    check_pixel(img, 1, 0, 0x80, 0x7f, 0x01);
    bsp_image_destroy(img);
    img = NULL;

    /* 1-bit gray: 0 -> 0, 1 -> 255. */
    harness_tmp_path(path, sizeof path, "gray1.png");
    unsigned char g0[1] = {0xa0}; /* 1 0 1 0 */
    unsigned char *grow[1] = {g0};
    REQUIRE(write_raw_png(path, 4, 1, PNG_COLOR_TYPE_GRAY, 1, PNG_INTERLACE_NONE, NULL, 0,
                          grow) == 0);
    CHECK_MSG(bsp_image_read_png(path, &img, &err) == BSP_OK, "%s", err.message);
    REQUIRE(img != NULL);
    check_pixel(img, 0, 0, 255, 255, 255);
    check_pixel(img, 1, 0, 0, 0, 0);
    check_pixel(img, 2, 0, 255, 255, 255);
    check_pixel(img, 3, 0, 0, 0, 0);
    bsp_image_destroy(img);
    img = NULL;

    /* Adam7-interlaced RGB, 9 x 9. */
    harness_tmp_path(path, sizeof path, "interlaced.png");
    unsigned char data[9][27];
    unsigned char *irows[9];
    for (int y = 0; y < 9; y++) {
        for (int x = 0; x < 9; x++) {
            data[y][3 * x] = (unsigned char)(x * 20);
            data[y][3 * x + 1] = (unsigned char)(y * 20);
            data[y][3 * x + 2] = (unsigned char)(x * 9 + y);
        }
        irows[y] = data[y];
    }
    REQUIRE(write_raw_png(path, 9, 9, PNG_COLOR_TYPE_RGB, 8, PNG_INTERLACE_ADAM7, NULL, 0,
                          irows) == 0);
    CHECK_MSG(bsp_image_read_png(path, &img, &err) == BSP_OK, "%s", err.message);
    REQUIRE(img != NULL);
    for (int y = 0; y < 9; y++)
        for (int x = 0; x < 9; x++)
            check_pixel(img, x, y, x * 20, y * 20, x * 9 + y);
    bsp_image_destroy(img);
}

/* --- PPM ------------------------------------------------------------------------------ */

TEST(image_ppm_bytes)
{
    char path[512];
    harness_tmp_path(path, sizeof path, "out.ppm");
    bsp_image *img = make_sample_image(4, 3);
    REQUIRE(img != NULL);
    bsp_error err = {0};
    CHECK_EQ_INT(bsp_image_write_ppm(img, path, &err), BSP_OK);

    size_t len = 0;
    unsigned char *data = harness_read_file(path, &len);
    REQUIRE(data != NULL);
    static const char header[] = "P6\n4 3\n255\n";
    size_t hl = sizeof header - 1;
    CHECK_EQ_INT(len, hl + 4 * 3 * 3);
    if (len == hl + 4 * 3 * 3) {
        CHECK(memcmp(data, header, hl) == 0);
        for (int i = 0; i < 4 * 3 * 3; i++)
            CHECK_MSG(data[hl + (size_t)i] == expected_byte(img->rgb[i]),
                      "byte %d (%g): got %d, want %d", i, (double)img->rgb[i], data[hl + (size_t)i],
                      expected_byte(img->rgb[i]));
        CHECK_EQ_INT(data[hl + 4], 128); /* 0.5 */
        CHECK_EQ_INT(data[hl + 3], 0);   /* NaN */
        CHECK_EQ_INT(data[hl + 2], 255); /* 2.0 */
        CHECK_EQ_INT(data[hl + 0], 0);   /* -1 */
    }
    free(data);
    bsp_image_destroy(img);
}

TEST(image_write_by_extension)
{
    static const char *const names[] = {"ext.ppm", "ext.PPM", "ext.png", "ext", "ext.ppm.png",
                                        "ppm"};
    static const int is_ppm[] = {1, 1, 0, 0, 0, 0};
    bsp_image *img = make_sample_image(2, 2);
    REQUIRE(img != NULL);
    for (size_t i = 0; i < sizeof names / sizeof names[0]; i++) {
        char path[512];
        harness_tmp_path(path, sizeof path, names[i]);
        bsp_error err = {0};
        CHECK_MSG(bsp_image_write(img, path, &err) == BSP_OK, "%s: %s", names[i], err.message);
        size_t len = 0;
        unsigned char *data = harness_read_file(path, &len);
        CHECK(data != NULL && len >= 8);
        if (data && len >= 8) {
            if (is_ppm[i])
                CHECK_MSG(memcmp(data, "P6\n", 3) == 0, "%s should be PPM", names[i]);
            else
                CHECK_MSG(png_sig_cmp(data, 0, 8) == 0, "%s should be PNG", names[i]);
        }
        free(data);
    }
    bsp_image_destroy(img);
}

/* --- errors ----------------------------------------------------------------------------- */

TEST(image_write_errors)
{
    char path[512];
    harness_tmp_path(path, sizeof path, "no/such/dir/out.png");
    bsp_image *img = make_sample_image(2, 2);
    REQUIRE(img != NULL);

    bsp_error err = {0};
    CHECK_EQ_INT(bsp_image_write_png(img, path, &err), BSP_ERR_IO);
    CHECK_EQ_INT(err.status, BSP_ERR_IO);
    CHECK_STR_CONTAINS(err.message, path);
    CHECK_STR_CONTAINS(err.message, "No such file or directory");

    harness_tmp_path(path, sizeof path, "no/such/dir/out.ppm");
    memset(&err, 0, sizeof err);
    CHECK_EQ_INT(bsp_image_write_ppm(img, path, &err), BSP_ERR_IO);
    CHECK_EQ_INT(err.status, BSP_ERR_IO);
    CHECK_STR_CONTAINS(err.message, path);

    memset(&err, 0, sizeof err);
    CHECK_EQ_INT(bsp_image_write(img, path, &err), BSP_ERR_IO);
    CHECK_STR_CONTAINS(err.message, path);

    /* err may be NULL. */
    CHECK_EQ_INT(bsp_image_write_png(img, path, NULL), BSP_ERR_IO);
    CHECK_EQ_INT(bsp_image_write_ppm(img, path, NULL), BSP_ERR_IO);

    /* A directory is not writable as a file. */
    memset(&err, 0, sizeof err);
    CHECK_EQ_INT(bsp_image_write_png(img, harness_tmpdir(), &err), BSP_ERR_IO);
    CHECK_STR_CONTAINS(err.message, harness_tmpdir());

    /* Bad arguments. */
    harness_tmp_path(path, sizeof path, "never.png");
    CHECK_EQ_INT(bsp_image_write_png(NULL, path, &err), BSP_ERR_INVALID);
    CHECK_EQ_INT(bsp_image_write_ppm(NULL, path, &err), BSP_ERR_INVALID);
    CHECK_EQ_INT(bsp_image_write(img, NULL, &err), BSP_ERR_INVALID);
    bsp_image bogus = {0, 3, img->rgb};
    CHECK_EQ_INT(bsp_image_write_png(&bogus, path, NULL), BSP_ERR_INVALID);
    CHECK(access(path, F_OK) != 0);
    bsp_image_destroy(img);
}

TEST(image_read_errors)
{
    char path[512];
    bsp_error err = {0};
    bsp_image *img = (bsp_image *)&err; /* must be reset to NULL on failure */

    /* Missing file. */
    harness_tmp_path(path, sizeof path, "missing.png");
    CHECK_EQ_INT(bsp_image_read_png(path, &img, &err), BSP_ERR_IO);
    CHECK(img == NULL);
    CHECK_EQ_INT(err.status, BSP_ERR_IO);
    CHECK_STR_CONTAINS(err.message, path);
    CHECK_EQ_INT(bsp_image_read_png(path, &img, NULL), BSP_ERR_IO);

    /* Not a PNG (and one shorter than a signature). */
    harness_tmp_path(path, sizeof path, "text.png");
    static const char text[] = "this is not a PNG file, just some text\n";
    REQUIRE(spit(path, text, sizeof text - 1) == 0);
    memset(&err, 0, sizeof err);
    CHECK_EQ_INT(bsp_image_read_png(path, &img, &err), BSP_ERR_IO);
    CHECK(img == NULL);
    CHECK_STR_CONTAINS(err.message, path);
    REQUIRE(spit(path, "\x89PN", 3) == 0);
    memset(&err, 0, sizeof err);
    CHECK_EQ_INT(bsp_image_read_png(path, &img, &err), BSP_ERR_IO);
    CHECK_STR_CONTAINS(err.message, path);
    REQUIRE(spit(path, "", 0) == 0);
    CHECK_EQ_INT(bsp_image_read_png(path, &img, &err), BSP_ERR_IO);

    /* A real PNG, then truncated versions of it. */
    char good[512];
    harness_tmp_path(good, sizeof good, "good.png");
    bsp_image *src = make_sample_image(16, 16);
    REQUIRE(src != NULL);
    REQUIRE(bsp_image_write_png(src, good, NULL) == BSP_OK);
    bsp_image_destroy(src);
    size_t len = 0;
    unsigned char *data = harness_read_file(good, &len);
    REQUIRE(data != NULL);
    REQUIRE(len > 60);

    harness_tmp_path(path, sizeof path, "trunc40.png");
    REQUIRE(spit(path, data, 40) == 0);
    memset(&err, 0, sizeof err);
    img = (bsp_image *)&err;
    CHECK_EQ_INT(bsp_image_read_png(path, &img, &err), BSP_ERR_IO);
    CHECK(img == NULL);
    CHECK_EQ_INT(err.status, BSP_ERR_IO);
    CHECK_STR_CONTAINS(err.message, path);

    /* Cut inside the image data. */
    harness_tmp_path(path, sizeof path, "trunc_mid.png");
    REQUIRE(spit(path, data, len / 2 + 20) == 0);
    memset(&err, 0, sizeof err);
    CHECK_EQ_INT(bsp_image_read_png(path, &img, &err), BSP_ERR_IO);
    CHECK(img == NULL);
    CHECK_STR_CONTAINS(err.message, path);
    CHECK_EQ_INT(bsp_image_read_png(path, &img, NULL), BSP_ERR_IO);

    /* Missing the IEND chunk. */
    harness_tmp_path(path, sizeof path, "trunc_end.png");
    REQUIRE(spit(path, data, len - 12) == 0);
    memset(&err, 0, sizeof err);
    CHECK_EQ_INT(bsp_image_read_png(path, &img, &err), BSP_ERR_IO);
    CHECK(img == NULL);
    CHECK_STR_CONTAINS(err.message, path);

    /* A corrupted IHDR CRC. */
    harness_tmp_path(path, sizeof path, "badcrc.png");
    data[30] ^= 0xff;
    REQUIRE(spit(path, data, len) == 0);
    memset(&err, 0, sizeof err);
    CHECK_EQ_INT(bsp_image_read_png(path, &img, &err), BSP_ERR_IO);
    CHECK(img == NULL);
    CHECK_STR_CONTAINS(err.message, path);
    free(data);

    /* The whole file still reads. */
    CHECK_EQ_INT(bsp_image_read_png(good, &img, &err), BSP_OK);
    CHECK(img != NULL && img->width == 16 && img->height == 16);
    bsp_image_destroy(img);

    /* Bad arguments. */
    CHECK_EQ_INT(bsp_image_read_png(NULL, &img, &err), BSP_ERR_INVALID);
    CHECK_EQ_INT(bsp_image_read_png(good, NULL, &err), BSP_ERR_INVALID);
}

/* --- progress bar ------------------------------------------------------------------------- */

TEST(progress_silent_off_terminal)
{
    FILE *fp = tmpfile();
    REQUIRE(fp != NULL);
    progress_bar *p = progress_create(fp, "render");
    CHECK(p != NULL);
    CHECK(!progress_enabled(p));
    for (int i = 0; i <= 100; i++)
        progress_update(p, i / 100.0);
    progress_update(p, NAN);
    progress_update(p, -1.0);
    progress_update(p, 7.0);
    progress_finish(p);
    fflush(fp);
    CHECK_EQ_INT(ftell(fp), 0);
    fseek(fp, 0, SEEK_END);
    CHECK_EQ_INT(ftell(fp), 0);
    fclose(fp);

    /* NULL is accepted everywhere. */
    progress_update(NULL, 0.5);
    progress_finish(NULL);
    CHECK(!progress_enabled(NULL));
}

/* Reads what is available on FD into BUF (NUL-terminated) until NEEDLE shows
 * up or a second passes without data. */
static size_t read_until(int fd, char *buf, size_t size, const char *needle)
{
    size_t n = 0;
    buf[0] = '\0';
    while (n + 1 < size && !strstr(buf, needle)) {
        struct pollfd pfd = {fd, POLLIN, 0};
        if (poll(&pfd, 1, 1000) <= 0)
            break;
        ssize_t got = read(fd, buf + n, size - 1 - n);
        if (got <= 0)
            break;
        n += (size_t)got;
        buf[n] = '\0';
    }
    return n;
}

TEST(progress_draws_on_terminal)
{
    int master = posix_openpt(O_RDWR | O_NOCTTY);
    if (master < 0)
        harness_skip("no pseudo-terminal: %s", strerror(errno));
    const char *slave_name = NULL;
    if (grantpt(master) != 0 || unlockpt(master) != 0 || !(slave_name = ptsname(master))) {
        close(master);
        harness_skip("pseudo-terminal setup failed");
    }
    int slave = open(slave_name, O_RDWR | O_NOCTTY);
    if (slave < 0) {
        close(master);
        harness_skip("cannot open %s", slave_name);
    }
    FILE *out = fdopen(slave, "w");
    if (!out) {
        close(slave);
        close(master);
        harness_skip("fdopen failed");
    }

    const char *saved = getenv("BSPRAY_NO_PROGRESS");
    char *saved_copy = saved ? strdup(saved) : NULL;
    unsetenv("BSPRAY_NO_PROGRESS");

    char buf[4096];
    progress_bar *p = progress_create(out, "render");
    CHECK(p != NULL);
    CHECK(progress_enabled(p));
    progress_update(p, 0.5); /* the first update always draws */
    progress_update(p, 0.6); /* too soon: skipped */
    progress_finish(p);
    read_until(master, buf, sizeof buf, "\n");
    CHECK_STR_CONTAINS(buf, "\rrender [##########          ]  50%");
    CHECK_STR_CONTAINS(buf, "left");
    CHECK(strstr(buf, " 60%") == NULL);
    CHECK_STR_CONTAINS(buf, "\rrender [####################] 100%");
    CHECK_STR_CONTAINS(buf, "\n");

    /* BSPRAY_NO_PROGRESS turns it off even on a terminal. */
    setenv("BSPRAY_NO_PROGRESS", "1", 1);
    p = progress_create(out, "render");
    CHECK(p != NULL);
    CHECK(!progress_enabled(p));
    progress_update(p, 0.5);
    progress_finish(p);
    fputs("END\n", out);
    fflush(out);
    read_until(master, buf, sizeof buf, "END");
    CHECK_MSG(strncmp(buf, "END", 3) == 0, "unexpected output: '%s'", buf);

    if (saved_copy)
        setenv("BSPRAY_NO_PROGRESS", saved_copy, 1);
    else
        unsetenv("BSPRAY_NO_PROGRESS");
    free(saved_copy);
    fclose(out);
    close(master);
}
