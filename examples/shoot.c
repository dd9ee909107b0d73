/*
 * shoot.c — libbspray from the outside: load a scene, build the default
 * structure (the SAH kd-tree), then answer a closest-hit query, a shadow
 * query and a batch of rays on every core.
 *
 *   cc shoot.c $(pkg-config --cflags --libs --static bspray) -o shoot
 *   ./shoot [SCENE [G]]      (default: spd:balls, a built-in SPD scene; G 256)
 *
 * It prints the closest hit of a ray from the scene's eye through the centre
 * of its view, whether a segment from that hit to the first light is
 * blocked, and how many rays of a G x G grid of eye rays hit something.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include <bspray/bspray.h>

int main(int argc, char **argv)
{
    const char *path = argc > 1 ? argv[1] : "spd:balls";
    const int G = argc > 2 ? atoi(argv[2]) : 256;
    if (G < 1 || G > 4096) {
        fprintf(stderr, "shoot: the grid size G must be from 1 to 4096\n");
        return 2;
    }
    bsp_scene *scene;
    bsp_error err;
    if (bsp_scene_load(path, &scene, &err) != BSP_OK) {
        fprintf(stderr, "shoot: %s\n", err.message);
        return 1;
    }
    bsp_accel *accel;
    if (bsp_accel_build(scene, NULL, &accel, &err) != BSP_OK) { /* NULL: the defaults */
        fprintf(stderr, "shoot: %s\n", err.message);
        bsp_scene_destroy(scene);
        return 1;
    }
    int status = 1;
    bsp_ray *rays = NULL;
    bsp_hit *hits = NULL;
    const bsp_camera *cam = bsp_scene_camera(scene);
    bsp_vec3 eye = cam ? cam->from : bsp_v3(0, 0, 10), at = cam ? cam->at : bsp_v3(0, 0, 0);
    bsp_vec3 dir = bsp_v3(at.x - eye.x, at.y - eye.y, at.z - eye.z);

    /* one query per thread: its mailbox and counters */
    bsp_query *q = bsp_query_create(accel);
    if (!q) {
        fprintf(stderr, "shoot: out of memory\n");
        goto done;
    }
    bsp_ray ray = {eye, dir, 0.0, INFINITY};
    bsp_hit hit;
    if (bsp_intersect(accel, q, &ray, &hit)) {
        printf("centre ray: primitive %u at t = %.17g\n", hit.prim, hit.t);
        if (bsp_scene_light_count(scene) > 0) {
            /* a shadow ray from the hit to the light, leaving out the
             * primitive it starts on; t in [0, 1] spans the segment */
            bsp_vec3 p =
                bsp_v3(eye.x + hit.t * dir.x, eye.y + hit.t * dir.y, eye.z + hit.t * dir.z);
            bsp_vec3 l = bsp_scene_light(scene, 0)->pos;
            bsp_ray shadow = {p, bsp_v3(l.x - p.x, l.y - p.y, l.z - p.z), 0.0, 1.0};
            printf("light 0 is %s\n",
                   bsp_occluded_from(accel, q, &shadow, hit.prim) ? "blocked" : "visible");
        }
    } else {
        printf("centre ray: miss\n");
    }
    bsp_query_destroy(q);

    /* a batch: a G x G grid of rays from the eye around the centre ray */
    rays = malloc((size_t)G * G * sizeof *rays);
    hits = malloc((size_t)G * G * sizeof *hits);
    if (!rays || !hits) {
        fprintf(stderr, "shoot: out of memory\n");
        goto done;
    }
    /* R and U: perpendicular to DIR and to each other, each as long as DIR,
     * so the grid spans about 53 degrees */
    bsp_vec3 up = cam ? cam->up : bsp_v3(0, 1, 0);
    bsp_vec3 r = bsp_v3(dir.y * up.z - dir.z * up.y, dir.z * up.x - dir.x * up.z,
                        dir.x * up.y - dir.y * up.x);
    bsp_vec3 u =
        bsp_v3(r.y * dir.z - r.z * dir.y, r.z * dir.x - r.x * dir.z, r.x * dir.y - r.y * dir.x);
    double len = sqrt(dir.x * dir.x + dir.y * dir.y + dir.z * dir.z);
    double rl = sqrt(r.x * r.x + r.y * r.y + r.z * r.z),
           ul = sqrt(u.x * u.x + u.y * u.y + u.z * u.z);
    if (!(rl > 0.0 && ul > 0.0)) { /* UP along DIR: any other axis will do */
        fprintf(stderr, "shoot: the view direction is parallel to up\n");
        goto done;
    }
    for (int j = 0; j < G; j++)
        for (int i = 0; i < G; i++) {
            double a = ((i + 0.5) / G - 0.5) * len / rl, b = ((j + 0.5) / G - 0.5) * len / ul;
            bsp_vec3 d = bsp_v3(dir.x + a * r.x + b * u.x, dir.y + a * r.y + b * u.y,
                                dir.z + a * r.z + b * u.z);
            rays[j * G + i] = (bsp_ray){eye, d, 0.0, INFINITY};
        }
    bsp_query_counters c;
    if (bsp_intersect_batch(accel, rays, NULL, (size_t)G * G, 0, hits, &c, &err) != BSP_OK) {
        fprintf(stderr, "shoot: %s\n", err.message);
        goto done;
    }
    size_t n_hit = 0;
    for (size_t i = 0; i < (size_t)G * G; i++)
        n_hit += hits[i].prim != BSP_NO_PRIM;
    printf("grid: %zu of %d rays hit; %.2f tests and %.2f traversal steps per ray\n", n_hit, G * G,
           (double)c.isect_tests / (double)c.rays, (double)c.traversal_steps / (double)c.rays);
    status = 0;
done: /* every way out frees what was made (free(NULL) does nothing) */
    free(rays);
    free(hits);
    bsp_accel_destroy(accel);
    bsp_scene_destroy(scene);
    return status;
}
