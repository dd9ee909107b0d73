/*
 * image.c — bsp_image: creation, and writing/reading as 8-bit RGB PNG
 * (through libpng) and binary PPM (P6). Float values are clamped to [0,1]
 * and quantized with (int)(v*255 + 0.5); NaN is written as 0. Errors are
 * reported through bsp_error, never printed.
 */
#include <errno.h>
#include <limits.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <png.h>

#include "bspray/render.h"
#include "util/errno_text.h"

static bsp_status image_fail(bsp_error *err, bsp_status status, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));

static bsp_status image_fail(bsp_error *err, bsp_status status, const char *fmt, ...)
{
    if (!err)
        return status;
    err->status = status;
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(err->message, sizeof err->message, fmt, ap);
    va_end(ap);
    return status;
}

static int image_valid(const bsp_image *img)
{
    return img && img->rgb && img->width > 0 && img->height > 0 &&
           (long long)img->width <= BSP_IMAGE_MAX_PIXELS / img->height;
}

/* Clamps to [0,1] and maps to 0..255; NaN gives 0. */
static unsigned char quantize(float v)
{
    if (!(v > 0.0f)) /* NaN, zero, negative */
        return 0;
    if (v >= 1.0f)
        return 255;
    return (unsigned char)(int)((double)v * 255.0 + 0.5);
}

/* Fills ROW (width*3 bytes) with image row Y quantized. */
static void quantize_row(const bsp_image *img, int y, unsigned char *row)
{
    size_t n = (size_t)img->width * 3;
    const float *src = img->rgb + (size_t)y * n;
    for (size_t i = 0; i < n; i++)
        row[i] = quantize(src[i]);
}

bsp_image *bsp_image_create(int width, int height)
{
    if (width <= 0 || height <= 0)
        return NULL;
    if ((long long)width > BSP_IMAGE_MAX_PIXELS / height)
        return NULL;
    bsp_image *img = malloc(sizeof *img);
    if (!img)
        return NULL;
    img->width = width;
    img->height = height;
    img->rgb = calloc((size_t)width * (size_t)height * 3, sizeof *img->rgb);
    if (!img->rgb) {
        free(img);
        return NULL;
    }
    return img;
}

void bsp_image_destroy(bsp_image *img)
{
    if (!img)
        return;
    free(img->rgb);
    free(img);
}

/* --- libpng error handling ---------------------------------------------------- */

/* Where the error callback leaves libpng's message. */
typedef struct png_err_ctx {
    char message[256];
} png_err_ctx;

static void png_error_cb(png_structp png, png_const_charp msg)
{
    png_err_ctx *ctx = png_get_error_ptr(png);
    if (ctx)
        snprintf(ctx->message, sizeof ctx->message, "%s", msg ? msg : "unknown libpng error");
    png_longjmp(png, 1);
}

static void png_warning_cb(png_structp png, png_const_charp msg)
{
    (void)png;
    (void)msg; /* the library never prints */
}

/* --- PNG writing ---------------------------------------------------------------- */

bsp_status bsp_image_write_png(const bsp_image *img, const char *path, bsp_error *err)
{
    if (!path)
        return image_fail(err, BSP_ERR_INVALID, "PNG write: no path given");
    if (!image_valid(img))
        return image_fail(err, BSP_ERR_INVALID, "%s: invalid image", path);

    /* Everything the error path frees is set up before setjmp and not
     * modified afterwards, so no local needs to be volatile. */
    unsigned char *row = malloc((size_t)img->width * 3);
    if (!row)
        return image_fail(err, BSP_ERR_NOMEM, "%s: out of memory", path);
    FILE *fp = fopen(path, "wb");
    if (!fp) {
        int e = errno;
        free(row);
        return image_fail(err, BSP_ERR_IO, "%s: cannot open for writing: %s", path,
                          ERRNO_TEXT(e));
    }
    png_err_ctx ctx = {{0}};
    png_structp png =
        png_create_write_struct(PNG_LIBPNG_VER_STRING, &ctx, png_error_cb, png_warning_cb);
    png_infop info = png ? png_create_info_struct(png) : NULL;
    if (!png || !info) {
        png_destroy_write_struct(png ? &png : NULL, NULL);
        fclose(fp);
        free(row);
        return image_fail(err, BSP_ERR_NOMEM, "%s: out of memory", path);
    }

    if (setjmp(png_jmpbuf(png))) {
        png_destroy_write_struct(&png, &info);
        fclose(fp);
        free(row);
        return image_fail(err, BSP_ERR_IO, "%s: cannot write PNG: %s", path, ctx.message);
    }

    png_init_io(png, fp);
    png_set_IHDR(png, info, (png_uint_32)img->width, (png_uint_32)img->height, 8,
                 PNG_COLOR_TYPE_RGB, PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT,
                 PNG_FILTER_TYPE_DEFAULT);
    png_write_info(png, info);
    for (int y = 0; y < img->height; y++) {
        quantize_row(img, y, row);
        png_write_row(png, row);
    }
    png_write_end(png, info);
    png_destroy_write_struct(&png, &info);
    free(row);

    if (fflush(fp) != 0 || ferror(fp)) {
        int e = errno;
        fclose(fp);
        return image_fail(err, BSP_ERR_IO, "%s: write error: %s", path, ERRNO_TEXT(e));
    }
    if (fclose(fp) != 0)
        return image_fail(err, BSP_ERR_IO, "%s: write error: %s", path, ERRNO_TEXT(errno));
    return BSP_OK;
}

/* --- PPM writing ------------------------------------------------------------------ */

bsp_status bsp_image_write_ppm(const bsp_image *img, const char *path, bsp_error *err)
{
    if (!path)
        return image_fail(err, BSP_ERR_INVALID, "PPM write: no path given");
    if (!image_valid(img))
        return image_fail(err, BSP_ERR_INVALID, "%s: invalid image", path);

    size_t rowbytes = (size_t)img->width * 3;
    unsigned char *row = malloc(rowbytes);
    if (!row)
        return image_fail(err, BSP_ERR_NOMEM, "%s: out of memory", path);
    FILE *fp = fopen(path, "wb");
    if (!fp) {
        int e = errno;
        free(row);
        return image_fail(err, BSP_ERR_IO, "%s: cannot open for writing: %s", path,
                          ERRNO_TEXT(e));
    }
    int ok = fprintf(fp, "P6\n%d %d\n255\n", img->width, img->height) > 0;
    for (int y = 0; ok && y < img->height; y++) {
        quantize_row(img, y, row);
        ok = fwrite(row, 1, rowbytes, fp) == rowbytes;
    }
    free(row);
    int e = errno;
    if (ok && fflush(fp) != 0) {
        ok = 0;
        e = errno;
    }
    if (fclose(fp) != 0 && ok) {
        ok = 0;
        e = errno;
    }
    if (!ok)
        return image_fail(err, BSP_ERR_IO, "%s: write error: %s", path, ERRNO_TEXT(e));
    return BSP_OK;
}

/* --- By extension ------------------------------------------------------------------- */

static int has_ppm_extension(const char *path)
{
    size_t n = strlen(path);
    if (n < 4)
        return 0;
    const char *ext = path + n - 4;
    static const char want[] = ".ppm";
    for (int i = 0; i < 4; i++) {
        char c = ext[i];
        if (c >= 'A' && c <= 'Z')
            c = (char)(c - 'A' + 'a');
        if (c != want[i])
            return 0;
    }
    return 1;
}

bsp_status bsp_image_write(const bsp_image *img, const char *path, bsp_error *err)
{
    if (!path)
        return image_fail(err, BSP_ERR_INVALID, "image write: no path given");
    if (has_ppm_extension(path))
        return bsp_image_write_ppm(img, path, err);
    return bsp_image_write_png(img, path, err);
}

/* --- PNG reading ---------------------------------------------------------------------- */

bsp_status bsp_image_read_png(const char *path, bsp_image **out, bsp_error *err)
{
    if (out)
        *out = NULL;
    if (!path || !out)
        return image_fail(err, BSP_ERR_INVALID, "PNG read: %s", path ? "no output" : "no path");

    FILE *fp = fopen(path, "rb");
    if (!fp) {
        int e = errno;
        return image_fail(err, BSP_ERR_IO, "%s: cannot open for reading: %s", path,
                          ERRNO_TEXT(e));
    }
    unsigned char sig[8];
    if (fread(sig, 1, sizeof sig, fp) != sizeof sig || png_sig_cmp(sig, 0, sizeof sig) != 0) {
        fclose(fp);
        return image_fail(err, BSP_ERR_IO, "%s: not a PNG file", path);
    }

    png_err_ctx ctx = {{0}};
    png_structp png =
        png_create_read_struct(PNG_LIBPNG_VER_STRING, &ctx, png_error_cb, png_warning_cb);
    png_infop info = png ? png_create_info_struct(png) : NULL;
    if (!png || !info) {
        png_destroy_read_struct(png ? &png : NULL, NULL, NULL);
        fclose(fp);
        return image_fail(err, BSP_ERR_NOMEM, "%s: out of memory", path);
    }

    /* Allocated after setjmp, so volatile: their values must survive longjmp. */
    bsp_image *volatile img = NULL;
    unsigned char *volatile pixels = NULL;
    png_bytep *volatile rows = NULL;
    volatile bsp_status fail_status = BSP_ERR_IO;

    if (setjmp(png_jmpbuf(png))) {
        png_destroy_read_struct(&png, &info, NULL);
        fclose(fp);
        free(rows);
        free(pixels);
        bsp_image_destroy(img);
        if (fail_status == BSP_ERR_IO)
            return image_fail(err, BSP_ERR_IO, "%s: cannot read PNG: %s", path, ctx.message);
        return image_fail(err, fail_status, "%s: %s", path, ctx.message);
    }

    png_init_io(png, fp);
    png_set_sig_bytes(png, (int)sizeof sig);
    png_read_info(png, info);

    png_uint_32 w = png_get_image_width(png, info);
    png_uint_32 h = png_get_image_height(png, info);
    int color_type = png_get_color_type(png, info);
    int bit_depth = png_get_bit_depth(png, info);

    /* Convert everything to 8-bit RGB. */
    if (color_type == PNG_COLOR_TYPE_PALETTE)
        png_set_palette_to_rgb(png);
    if (color_type == PNG_COLOR_TYPE_GRAY && bit_depth < 8)
        png_set_expand_gray_1_2_4_to_8(png);
    if (png_get_valid(png, info, PNG_INFO_tRNS))
        png_set_tRNS_to_alpha(png);
    if (bit_depth == 16)
        png_set_strip_16(png);
    if (color_type == PNG_COLOR_TYPE_GRAY || color_type == PNG_COLOR_TYPE_GRAY_ALPHA)
        png_set_gray_to_rgb(png);
    png_set_strip_alpha(png);
    (void)png_set_interlace_handling(png);
    png_read_update_info(png, info);

    if (png_get_bit_depth(png, info) != 8 || png_get_channels(png, info) != 3) {
        snprintf(ctx.message, sizeof ctx.message, "unsupported PNG format");
        png_longjmp(png, 1);
    }
    if (w == 0 || h == 0 || w > INT_MAX || h > INT_MAX ||
        (long long)w > BSP_IMAGE_MAX_PIXELS / (long long)h) {
        fail_status = BSP_ERR_LIMIT;
        snprintf(ctx.message, sizeof ctx.message, "PNG of %lu x %lu pixels is too large",
                 (unsigned long)w, (unsigned long)h);
        png_longjmp(png, 1);
    }
    size_t rowbytes = png_get_rowbytes(png, info);
    if (rowbytes != (size_t)w * 3) {
        snprintf(ctx.message, sizeof ctx.message, "unexpected PNG row size");
        png_longjmp(png, 1);
    }

    img = bsp_image_create((int)w, (int)h);
    pixels = malloc(rowbytes * h);
    rows = malloc(sizeof *rows * h);
    if (!img || !pixels || !rows) {
        fail_status = BSP_ERR_NOMEM;
        snprintf(ctx.message, sizeof ctx.message, "out of memory");
        png_longjmp(png, 1);
    }
    for (png_uint_32 y = 0; y < h; y++)
        rows[y] = pixels + (size_t)y * rowbytes;
    png_read_image(png, rows);
    png_read_end(png, NULL);

    size_t n = rowbytes * h;
    for (size_t i = 0; i < n; i++)
        img->rgb[i] = (float)(pixels[i] / 255.0);

    png_destroy_read_struct(&png, &info, NULL);
    fclose(fp);
    free(rows);
    free(pixels);
    *out = img;
    return BSP_OK;
}
