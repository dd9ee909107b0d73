/*
 * shoot_cxx.cpp — libbspray from C++: the program of shoot.c, with the
 * library's handles owned by std::unique_ptr (each with its destroy function)
 * and the ray batch in std::vector, so that every way out frees them.
 *
 *   c++ -std=c++11 shoot_cxx.cpp $(pkg-config --cflags --libs --static bspray) -o shoot_cxx
 *   ./shoot_cxx [SCENE [G]]      (default: spd:balls; G 256)
 *
 * The public headers declare the API extern "C", so a C++ program includes
 * them as they are. It prints what shoot.c prints, to the bit: the rays are
 * made by the same operations in the same order.
 */
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <vector>

#include <bspray/bspray.h>

namespace
{

struct scene_deleter {
    void operator()(bsp_scene *s) const
    {
        bsp_scene_destroy(s);
    }
};
struct accel_deleter {
    void operator()(bsp_accel *a) const
    {
        bsp_accel_destroy(a);
    }
};
struct query_deleter {
    void operator()(bsp_query *q) const
    {
        bsp_query_destroy(q);
    }
};
using scene_ptr = std::unique_ptr<bsp_scene, scene_deleter>;
using accel_ptr = std::unique_ptr<bsp_accel, accel_deleter>;
using query_ptr = std::unique_ptr<bsp_query, query_deleter>;

bsp_vec3 cross(bsp_vec3 a, bsp_vec3 b)
{
    return bsp_v3(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x);
}

double length(bsp_vec3 a)
{
    return std::sqrt(a.x * a.x + a.y * a.y + a.z * a.z);
}

} // namespace

int main(int argc, char **argv)
{
    const char *path = argc > 1 ? argv[1] : "spd:balls";
    const int G = argc > 2 ? std::atoi(argv[2]) : 256;
    if (G < 1 || G > 4096) {
        std::fprintf(stderr, "shoot_cxx: the grid size G must be from 1 to 4096\n");
        return 2;
    }
    bsp_error err;
    bsp_scene *raw_scene = nullptr;
    if (bsp_scene_load(path, &raw_scene, &err) != BSP_OK) {
        std::fprintf(stderr, "shoot_cxx: %s\n", err.message);
        return 1;
    }
    scene_ptr scene(raw_scene);
    bsp_accel *raw_accel = nullptr;
    if (bsp_accel_build(scene.get(), nullptr, &raw_accel, &err) != BSP_OK) { // the defaults
        std::fprintf(stderr, "shoot_cxx: %s\n", err.message);
        return 1;
    }
    accel_ptr accel(raw_accel);

    const bsp_camera *cam = bsp_scene_camera(scene.get());
    const bsp_vec3 eye = cam ? cam->from : bsp_v3(0, 0, 10), at = cam ? cam->at : bsp_v3(0, 0, 0);
    const bsp_vec3 dir = bsp_v3(at.x - eye.x, at.y - eye.y, at.z - eye.z);

    {
        query_ptr q(bsp_query_create(accel.get())); // one per thread: its mailbox and counters
        if (!q) {
            std::fprintf(stderr, "shoot_cxx: out of memory\n");
            return 1;
        }
        const bsp_ray ray = {eye, dir, 0.0, INFINITY};
        bsp_hit hit;
        if (bsp_intersect(accel.get(), q.get(), &ray, &hit)) {
            std::printf("centre ray: primitive %u at t = %.17g\n", hit.prim, hit.t);
            if (bsp_scene_light_count(scene.get()) > 0) {
                // the segment from the hit to the light, leaving out the primitive it starts on
                const bsp_vec3 p =
                    bsp_v3(eye.x + hit.t * dir.x, eye.y + hit.t * dir.y, eye.z + hit.t * dir.z);
                const bsp_vec3 l = bsp_scene_light(scene.get(), 0)->pos;
                const bsp_ray shadow = {p, bsp_v3(l.x - p.x, l.y - p.y, l.z - p.z), 0.0, 1.0};
                std::printf("light 0 is %s\n",
                            bsp_occluded_from(accel.get(), q.get(), &shadow, hit.prim) ? "blocked"
                                                                                       : "visible");
            }
        } else {
            std::printf("centre ray: miss\n");
        }
    }

    // a G x G grid of rays from the eye around the centre ray, on every core
    const bsp_vec3 up = cam ? cam->up : bsp_v3(0, 1, 0);
    const bsp_vec3 r = cross(dir, up), u = cross(r, dir);
    const double len = length(dir), rl = length(r), ul = length(u);
    if (!(rl > 0.0 && ul > 0.0)) {
        std::fprintf(stderr, "shoot_cxx: the view direction is parallel to up\n");
        return 1;
    }
    const std::size_t n = static_cast<std::size_t>(G) * static_cast<std::size_t>(G);
    std::vector<bsp_ray> rays(n);
    std::vector<bsp_hit> hits(n);
    for (int j = 0; j < G; j++)
        for (int i = 0; i < G; i++) {
            const double a = ((i + 0.5) / G - 0.5) * len / rl, b = ((j + 0.5) / G - 0.5) * len / ul;
            const bsp_vec3 d = bsp_v3(dir.x + a * r.x + b * u.x, dir.y + a * r.y + b * u.y,
                                      dir.z + a * r.z + b * u.z);
            rays[static_cast<std::size_t>(j) * G + i] = bsp_ray{eye, d, 0.0, INFINITY};
        }
    bsp_query_counters c;
    if (bsp_intersect_batch(accel.get(), rays.data(), nullptr, n, 0, hits.data(), &c, &err) !=
        BSP_OK) {
        std::fprintf(stderr, "shoot_cxx: %s\n", err.message);
        return 1;
    }
    std::size_t n_hit = 0;
    for (const bsp_hit &h : hits)
        n_hit += h.prim != BSP_NO_PRIM;
    std::printf("grid: %zu of %d rays hit; %.2f tests and %.2f traversal steps per ray\n", n_hit,
                G * G, static_cast<double>(c.isect_tests) / static_cast<double>(c.rays),
                static_cast<double>(c.traversal_steps) / static_cast<double>(c.rays));
    return 0;
}
