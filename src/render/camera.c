/*
 * camera.c — primary rays of an NFF camera.
 *
 * SPD protocol (BSP_SAMPLING_SPD): a file that says "resolution 512 512" is
 * traced with 513 x 513 rays through the pixel corners, and the NFF angle
 * spans the first to the last ray (NFF.TXT: "from the center of top pixel row
 * to bottom pixel row"). With W rays across, neighbouring rays are
 * 2 tan(angle/2) / (W - 1) apart on the image plane at distance 1.
 *
 * Pixel centres (BSP_SAMPLING_CENTRES): W pixels across, the angle spans the
 * outer pixel edges, so rays are 2 tan(angle/2) / W apart and start half a
 * step inside the edge.
 *
 * Pixels are square; the angle applies to the horizontal direction.
 *
 * Orthographic (the rays of sah-par): the same grid, with a window of the
 * given width in scene units in place of the angle, on the plane through
 * `from` perpendicular to the view; every ray starts on that plane and runs
 * along the view direction.
 */
#include <math.h>

#include "geom/vec.h"
#include "render/camera.h"

void camera_default_size(const bsp_camera *cam, bsp_sampling sampling, int *width, int *height)
{
    int extra = sampling == BSP_SAMPLING_SPD ? 1 : 0;
    *width = cam->res_x + extra;
    *height = cam->res_y + extra;
}

double camera_default_ortho_width(const bsp_camera *cam)
{
    return 2.0 * tan(cam->angle_deg * (BSP_PI / 360.0)) * v3_length(v3_sub(cam->at, cam->from));
}

void camera_rays_init(camera_rays *cr, const bsp_camera *cam, int width, int height,
                      bsp_sampling sampling, double ortho_width)
{
    cr->eye = cam->from;
    cr->forward = v3_normalize(v3_sub(cam->at, cam->from));
    cr->right = v3_normalize(v3_cross(cr->forward, cam->up));
    cr->up = v3_cross(cr->right, cr->forward);
    cr->width = width;
    cr->height = height;
    cr->ortho = ortho_width > 0.0;
    double half = cr->ortho ? 0.5 * ortho_width : tan(cam->angle_deg * (BSP_PI / 360.0));
    if (sampling == BSP_SAMPLING_SPD) /* a one-ray-wide image looks straight ahead */
        cr->step = width > 1 ? 2.0 * half / (double)(width - 1) : 0.0;
    else
        cr->step = 2.0 * half / (double)width;
    /* both conventions put the image centre on the view axis */
    cr->x0 = -0.5 * (double)(width - 1) * cr->step;
    cr->y0 = 0.5 * (double)(height - 1) * cr->step;
}

bsp_ray camera_ray(const camera_rays *cr, int x, int y)
{
    double sx = cr->x0 + (double)x * cr->step;
    double sy = cr->y0 - (double)y * cr->step;
    if (cr->ortho) {
        bsp_ray r;
        r.org = v3_add(cr->eye, v3_add(v3_scale(cr->right, sx), v3_scale(cr->up, sy)));
        r.dir = cr->forward;
        r.tmin = 0.0;
        r.tmax = INFINITY;
        return r;
    }
    bsp_vec3 d = v3_add(cr->forward, v3_add(v3_scale(cr->right, sx), v3_scale(cr->up, sy)));
    bsp_ray r;
    r.org = cr->eye;
    r.dir = v3_normalize(d);
    r.tmin = 0.0;
    r.tmax = INFINITY;
    return r;
}
