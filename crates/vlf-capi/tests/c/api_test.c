/*
 * The C API from C: layouts, error codes and messages, null and range checks, open from memory,
 * provenance, queries from several threads at once, what a field says about itself (format
 * version, bounds, parameters, packing), materials, cameras and lights, and opening with a cap on
 * a packed field's decoded size. Run by tests/c_programs.rs as
 *
 *   api_test FIELD TRIANGLES CONTENT_HASH_HEX INPUT_NAME VERSION FORMAT DIRECTIONS TILES
 *            SCENE MATERIALS CAMERAS LIGHTS CAMERA0_NAME MATERIAL_OF_0 PACKED UNPACKED_BYTES
 *
 * with the facts the Rust API reports: FIELD a field of one OBJ without materials, baked with
 * DIRECTIONS directions and TILES tiles, of format version FORMAT ("1.1"); SCENE a field of a glTF
 * with materials, cameras and lights, MATERIAL_OF_0 the material index of its triangle 0; PACKED
 * FIELD packed, which decodes to UNPACKED_BYTES. Prints each failed check and a closing
 * "api_test: N passed, N failed" line; exits 0 only if every check passed.
 */

#include <inttypes.h>
#include <math.h>
#include <pthread.h>
#include <stdalign.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "vlf.h"

/* The structs are the records of formats/rays.md, to the byte (the Rust side asserts the same). */
_Static_assert(sizeof(VlfRay) == 32, "VlfRay is a 32-byte rays-file record");
_Static_assert(alignof(VlfRay) == 4, "VlfRay is 4-aligned");
_Static_assert(offsetof(VlfRay, org) == 0 && offsetof(VlfRay, tmin) == 12, "VlfRay layout");
_Static_assert(offsetof(VlfRay, dir) == 16 && offsetof(VlfRay, tmax) == 28, "VlfRay layout");
_Static_assert(sizeof(VlfHit) == 16, "VlfHit is a 16-byte hits-file record");
_Static_assert(offsetof(VlfHit, t) == 0 && offsetof(VlfHit, prim) == 4, "VlfHit layout");
_Static_assert(offsetof(VlfHit, u) == 8 && offsetof(VlfHit, v) == 12, "VlfHit layout");
_Static_assert(sizeof(VlfStatus) == 4, "VlfStatus is an int32_t");
_Static_assert(VLF_OK == 0 && VLF_ERR_NULL_ARGUMENT == 1 && VLF_ERR_INVALID_ARGUMENT == 2, "stable codes");
_Static_assert(VLF_ERR_IO == 3 && VLF_ERR_FORMAT == 4 && VLF_ERR_INTERNAL == 5, "stable codes");
_Static_assert(VLF_ERR_OUT_OF_MEMORY == 6 && VLF_ERR_LIMIT == 7, "stable codes");
_Static_assert(VLF_AUTOMATIC == 0, "requested parameters: 0 = automatic");
_Static_assert(VLF_CAMERA_PERSPECTIVE == 1 && VLF_CAMERA_ORTHOGRAPHIC == 2, "camera kinds of formats/vlf.md");
_Static_assert(VLF_LIGHT_POINT == 1 && VLF_LIGHT_SPOT == 2 && VLF_LIGHT_DIRECTIONAL == 3, "light kinds");
_Static_assert(sizeof(VlfParameters) == 56 && offsetof(VlfParameters, lattice_n) == 24, "VlfParameters layout");
_Static_assert(sizeof(VlfOpenOptions) == 8, "VlfOpenOptions layout");
_Static_assert(VLF_NO_PRIM == 0xFFFFFFFFu && VLF_NO_INDEX == 0xFFFFFFFFu, "miss and absent-index markers");

static int passed, failed;

#define CHECK(cond)                                                                                  \
    do {                                                                                             \
        if (cond) {                                                                                  \
            passed++;                                                                                \
        } else {                                                                                     \
            failed++;                                                                                \
            fprintf(stderr, "%s:%d: check failed: %s (last error: %s)\n", __FILE__, __LINE__, #cond, \
                    vlf_last_error_message());                                                       \
        }                                                                                            \
    } while (0)

/* Whether the thread's last error message contains `part`. */
static int message_has(const char *part) { return strstr(vlf_last_error_message(), part) != NULL; }

static void hex(const uint8_t *bytes, size_t n, char *out) {
    size_t i;
    for (i = 0; i < n; i++) {
        sprintf(out + 2 * i, "%02x", bytes[i]);
    }
}

static void *read_all(const char *path, size_t *len) {
    FILE *f = fopen(path, "rb");
    long size;
    void *data;
    if (f == NULL || fseek(f, 0, SEEK_END) != 0 || (size = ftell(f)) < 0 || fseek(f, 0, SEEK_SET) != 0) {
        return NULL;
    }
    data = malloc((size_t)size + 1);
    if (data != NULL && fread(data, 1, (size_t)size, f) != (size_t)size) {
        free(data);
        data = NULL;
    }
    fclose(f);
    *len = (size_t)size;
    return data;
}

/* Rays from outside the bounding sphere towards points inside it, from a fixed-seed generator. */
#define RAY_COUNT 2000
static VlfRay rays[RAY_COUNT];
static VlfHit reference[RAY_COUNT];
static uint8_t reference_any[RAY_COUNT];

static float unit_random(uint64_t *state) {
    *state ^= *state << 13;
    *state ^= *state >> 7;
    *state ^= *state << 17;
    return (float)(*state >> 40) / (float)(1 << 24);
}

static void make_rays(const double center[3], double radius) {
    uint64_t state = 0x9E3779B97F4A7C15u;
    int i, k;
    for (i = 0; i < RAY_COUNT; i++) {
        for (k = 0; k < 3; k++) {
            double side = unit_random(&state) < 0.5f ? -1.0 : 1.0;
            double o = center[k] + side * radius * (1.2 + unit_random(&state));
            double target = center[k] + radius * (2.0 * unit_random(&state) - 1.0) * 0.7;
            rays[i].org[k] = (float)o;
            rays[i].dir[k] = (float)(target - o);
        }
        rays[i].tmin = 0.0f;
        rays[i].tmax = INFINITY;
    }
}

struct worker {
    const VlfField *field;
    int mismatches;
    int own_message_kept;
};

/* Traces every ray one by one and compares with the main thread's array answers; also fails a
 * call on purpose, so the main thread can check that error messages are per thread. */
static void *trace_worker(void *arg) {
    struct worker *w = arg;
    int i;
    for (i = 0; i < RAY_COUNT; i++) {
        VlfHit hit;
        uint8_t any = 2;
        if (vlf_closest_hit(w->field, &rays[i], &hit) != VLF_OK || memcmp(&hit, &reference[i], sizeof hit) != 0 ||
            vlf_any_hit(w->field, &rays[i], &any) != VLF_OK || any != reference_any[i]) {
            w->mismatches++;
        }
    }
    vlf_closest_hit(w->field, NULL, NULL);
    w->own_message_kept = strstr(vlf_last_error_message(), "`ray` is null") != NULL;
    return NULL;
}

/* A call made from a thread-specific data destructor, as its thread exits, after the library's
 * own per-thread message is freed: a status and a fixed message, never an abort. */
static pthread_key_t exit_key;
static VlfStatus at_exit_status = VLF_OK;
static int at_exit_message = 0;

static void at_thread_exit(void *value) {
    VlfField *f = NULL;
    (void)value;
    at_exit_status = vlf_open_path("/nonexistent/at-thread-exit.vlf", &f);
    at_exit_message = strstr(vlf_last_error_message(), "exiting") != NULL;
}

static void *exiting_thread(void *arg) {
    VlfField *f = NULL;
    (void)arg;
    /* A failure first, so that the thread holds a message the library frees as it exits. */
    if (vlf_open_path("/nonexistent/first.vlf", &f) == VLF_ERR_IO) {
        pthread_setspecific(exit_key, (void *)&exit_key);
    }
    return NULL;
}

static void calls_as_a_thread_exits(void) {
    pthread_t t;
    CHECK(pthread_key_create(&exit_key, at_thread_exit) == 0);
    CHECK(pthread_create(&t, NULL, exiting_thread, NULL) == 0);
    CHECK(pthread_join(t, NULL) == 0);
    CHECK(at_exit_status == VLF_ERR_IO && at_exit_message);
    pthread_key_delete(exit_key);
}

/* Format version, bounds, parameters and packing of FIELD (argv as main's). */
static void about_the_field(const VlfField *field, char **argv) {
    uint16_t major = 0, minor = 0;
    double lo[3], hi[3], center[3], radius = 0.0, both[5];
    uint8_t packed = 7;
    VlfParameters p;
    char version[16];
    int i;

    CHECK(vlf_format_version(field, &major, &minor) == VLF_OK);
    snprintf(version, sizeof version, "%u.%u", (unsigned)major, (unsigned)minor);
    CHECK(strcmp(version, argv[6]) == 0);
    CHECK(vlf_format_version(field, NULL, &minor) == VLF_ERR_NULL_ARGUMENT && message_has("`major` is null"));
    CHECK(vlf_format_version(field, &major, &major) == VLF_ERR_INVALID_ARGUMENT && message_has("overlap"));
    CHECK(vlf_format_version(NULL, &major, &minor) == VLF_ERR_NULL_ARGUMENT);

    /* The box lies inside the bounding sphere and is not empty. */
    CHECK(vlf_bounds(field, lo, hi) == VLF_OK && vlf_bounding_sphere(field, center, &radius) == VLF_OK);
    for (i = 0; i < 3; i++) {
        CHECK(lo[i] < hi[i] && lo[i] >= center[i] - radius && hi[i] <= center[i] + radius);
    }
    CHECK(vlf_bounds(field, both, both + 2) == VLF_ERR_INVALID_ARGUMENT && message_has("overlap"));
    CHECK(vlf_bounds(field, lo, NULL) == VLF_ERR_NULL_ARGUMENT && message_has("`max` is null"));

    CHECK(vlf_is_packed(field, &packed) == VLF_OK && packed == 0);
    CHECK(vlf_is_packed(field, NULL) == VLF_ERR_NULL_ARGUMENT);

    memset(&p, 0xff, sizeof p);
    CHECK(vlf_parameters(field, &p) == VLF_OK);
    CHECK(p.directions == (uint32_t)strtoul(argv[7], NULL, 10) && p.requested_directions == p.directions);
    CHECK(p.tiles == (uint32_t)strtoul(argv[8], NULL, 10) && p.requested_tiles == p.tiles);
    CHECK(p.directions == 2 * p.lattice_n * p.lattice_n + 1 && p.leaf_size >= 1 && p.max_depth <= 24);
    CHECK(p.margin > 0.0 && p.margin < radius && p.max_bytes > 0 && p.max_bytes_per_triangle > 0 && p.reserved == 0);
    CHECK(vlf_parameters(field, NULL) == VLF_ERR_NULL_ARGUMENT && message_has("`parameters` is null"));
    CHECK(vlf_parameters(field, (VlfParameters *)(void *)((char *)&p + 4)) == VLF_ERR_INVALID_ARGUMENT &&
          message_has("not aligned"));
}

/* Materials, cameras and lights of SCENE; FIELD has none. */
static void scene(char **argv) {
    VlfField *field = NULL, *plain = NULL;
    uint32_t count = 99, index = 0, triangles = 0, with_material = 0, i;
    VlfMaterial m;
    VlfCamera c;
    VlfLight l;

    CHECK(vlf_open_path(argv[1], &plain) == VLF_OK);
    CHECK(vlf_material_count(plain, &count) == VLF_OK && count == 0);
    CHECK(vlf_camera_count(plain, &count) == VLF_OK && count == 0);
    CHECK(vlf_light_count(plain, &count) == VLF_OK && count == 0);
    CHECK(vlf_triangle_material(plain, 0, &index) == VLF_OK && index == VLF_NO_INDEX);
    CHECK(vlf_material(plain, 0, &m) == VLF_ERR_INVALID_ARGUMENT && message_has("the field has 0 materials"));
    CHECK(vlf_camera(plain, 0, &c) == VLF_ERR_INVALID_ARGUMENT && message_has("the field has 0 cameras"));
    CHECK(vlf_light(plain, 0, &l) == VLF_ERR_INVALID_ARGUMENT && message_has("the field has 0 lights"));
    vlf_close(plain);

    CHECK(vlf_open_path(argv[9], &field) == VLF_OK && field != NULL);
    if (field == NULL) {
        return;
    }
    CHECK(vlf_material_count(field, &count) == VLF_OK && count == (uint32_t)strtoul(argv[10], NULL, 10));
    for (i = 0; i < count; i++) {
        CHECK(vlf_material(field, i, &m) == VLF_OK && m.name != NULL && m.ior > 0.0f && m.shininess >= 0.0f);
    }
    CHECK(vlf_material(field, count, &m) == VLF_ERR_INVALID_ARGUMENT && message_has("out of range"));
    CHECK(vlf_material(field, 0, NULL) == VLF_ERR_NULL_ARGUMENT && message_has("`material` is null"));
    CHECK(vlf_material_count(field, NULL) == VLF_ERR_NULL_ARGUMENT);
    CHECK(vlf_triangle_count(field, &triangles) == VLF_OK);
    CHECK(vlf_triangle_material(field, 0, &index) == VLF_OK && index == (uint32_t)strtoul(argv[14], NULL, 10));
    for (i = 0; i < triangles; i++) {
        index = 0;
        CHECK(vlf_triangle_material(field, i, &index) == VLF_OK && (index < count || index == VLF_NO_INDEX));
        with_material += index != VLF_NO_INDEX;
    }
    CHECK(with_material > 0);
    CHECK(vlf_triangle_material(field, triangles, &index) == VLF_ERR_INVALID_ARGUMENT && message_has("out of range"));
    CHECK(vlf_triangle_material(field, 0, NULL) == VLF_ERR_NULL_ARGUMENT);

    CHECK(vlf_camera_count(field, &count) == VLF_OK && count == (uint32_t)strtoul(argv[11], NULL, 10));
    CHECK(count > 0 && vlf_camera(field, 0, &c) == VLF_OK);
    CHECK(c.name_len == strlen(argv[13]) && memcmp(c.name, argv[13], c.name_len) == 0);
    CHECK(c.projection == VLF_CAMERA_PERSPECTIVE && c.yfov > 0.0f && c.yfov < 3.2f && c.xmag == 0.0f);
    CHECK(fabs(c.forward[0] * c.forward[0] + c.forward[1] * c.forward[1] + c.forward[2] * c.forward[2] - 1.0) < 1e-3);
    CHECK(fabs(c.forward[0] * c.up[0] + c.forward[1] * c.up[1] + c.forward[2] * c.up[2]) < 1e-3);
    CHECK(c.znear >= 0.0f && (c.zfar == 0.0f || c.zfar > c.znear));
    CHECK(vlf_camera(field, count, &c) == VLF_ERR_INVALID_ARGUMENT && message_has("cameras"));
    CHECK(vlf_camera(field, 0, NULL) == VLF_ERR_NULL_ARGUMENT);
    CHECK(vlf_camera_count(NULL, &count) == VLF_ERR_NULL_ARGUMENT);

    CHECK(vlf_light_count(field, &count) == VLF_OK && count == (uint32_t)strtoul(argv[12], NULL, 10));
    for (i = 0; i < count; i++) {
        CHECK(vlf_light(field, i, &l) == VLF_OK && l.kind >= VLF_LIGHT_POINT && l.kind <= VLF_LIGHT_DIRECTIONAL);
        CHECK(l.intensity > 0.0f && l.range >= 0.0f && (l.kind == VLF_LIGHT_SPOT || l.outer_cone == 0.0f));
    }
    CHECK(vlf_light(field, count, &l) == VLF_ERR_INVALID_ARGUMENT && message_has("lights"));
    CHECK(vlf_light(field, 0, (VlfLight *)(void *)((char *)&l + 1)) == VLF_ERR_INVALID_ARGUMENT);
    CHECK(vlf_light_count(field, NULL) == VLF_ERR_NULL_ARGUMENT);
    vlf_close(field);
}

/* PACKED opened with and without a cap on its decoded size, from its path and from memory. */
static void packed_with_a_cap(char **argv) {
    VlfField *field = (VlfField *)&argv;
    VlfOpenOptions options;
    uint64_t unpacked = strtoull(argv[16], NULL, 10);
    uint8_t packed = 0;
    void *bytes;
    size_t len = 0;

    options.max_unpacked_bytes = unpacked - 1;
    CHECK(vlf_open_path_ex(argv[15], &options, &field) == VLF_ERR_LIMIT && field == NULL &&
          message_has("vlf_open_path_ex") && message_has("more than the limit"));
    options.max_unpacked_bytes = unpacked;
    CHECK(vlf_open_path_ex(argv[15], &options, &field) == VLF_OK && field != NULL);
    CHECK(vlf_is_packed(field, &packed) == VLF_OK && packed == 1);
    vlf_close(field);
    field = NULL;
    CHECK(vlf_open_path_ex(argv[15], NULL, &field) == VLF_OK && field != NULL);
    vlf_close(field);
    options.max_unpacked_bytes = 0; /* no cap */
    CHECK(vlf_open_path_ex(argv[15], &options, &field) == VLF_OK);
    vlf_close(field);
    /* A raw field is not decoded: a cap does not apply to it. */
    options.max_unpacked_bytes = 1;
    CHECK(vlf_open_path_ex(argv[1], &options, &field) == VLF_OK);
    vlf_close(field);
    CHECK(vlf_open_path_ex(NULL, &options, &field) == VLF_ERR_NULL_ARGUMENT && field == NULL);
    CHECK(vlf_open_path_ex(argv[15], (const VlfOpenOptions *)(const void *)((const char *)&options + 1), &field) ==
              VLF_ERR_INVALID_ARGUMENT &&
          message_has("`options` is not aligned"));

    bytes = read_all(argv[15], &len);
    CHECK(bytes != NULL);
    if (bytes != NULL) {
        options.max_unpacked_bytes = unpacked - 1;
        CHECK(vlf_open_memory_ex(bytes, len, &options, &field) == VLF_ERR_LIMIT && field == NULL &&
              message_has("vlf_open_memory_ex"));
        options.max_unpacked_bytes = unpacked;
        CHECK(vlf_open_memory_ex(bytes, len, &options, &field) == VLF_OK && field != NULL);
        CHECK(vlf_is_packed(field, &packed) == VLF_OK && packed == 1);
        vlf_close(field);
        CHECK(vlf_open_memory_ex(NULL, len, NULL, &field) == VLF_ERR_NULL_ARGUMENT);
        CHECK(vlf_open_memory_ex(bytes, len, NULL, NULL) == VLF_ERR_NULL_ARGUMENT);
        free(bytes);
    }
}

int main(int argc, char **argv) {
    VlfField *field = NULL, *from_memory = NULL;
    uint32_t triangles = 0, expected_triangles;
    uint8_t hash[32], hash2[32], input_hash[32], any = 7;
    char hash_hex[65];
    double center[3], radius = 0.0;
    float vertices[9];
    VlfProvenance prov;
    VlfHit hit, hits[2];
    VlfRay ray = {{0.0f, 0.0f, 0.0f}, 0.0f, {0.0f, 0.0f, 1.0f}, INFINITY};
    void *bytes;
    size_t len = 0, i;
    static const char garbage[256] = "not a field at all";
    static char sentinel;
    /* A buffer aligned for VlfRay, to build a misaligned pointer into. */
    alignas(8) unsigned char raw[sizeof(VlfRay) + 8];

    if (argc != 17) {
        fprintf(stderr, "usage: api_test FIELD TRIANGLES CONTENT_HASH_HEX INPUT_NAME VERSION FORMAT DIRECTIONS "
                        "TILES SCENE MATERIALS CAMERAS LIGHTS CAMERA0_NAME MATERIAL_OF_0 PACKED UNPACKED_BYTES\n");
        return 2;
    }
    expected_triangles = (uint32_t)strtoul(argv[2], NULL, 10);

    /* Version and status names. */
    CHECK(strcmp(vlf_version(), argv[5]) == 0);
    CHECK(strcmp(vlf_status_name(VLF_ERR_IO), "VLF_ERR_IO") == 0);
    CHECK(strcmp(vlf_status_name(VLF_OK), "VLF_OK") == 0);
    CHECK(strcmp(vlf_status_name(VLF_ERR_OUT_OF_MEMORY), "VLF_ERR_OUT_OF_MEMORY") == 0);
    CHECK(strcmp(vlf_status_name(VLF_ERR_LIMIT), "VLF_ERR_LIMIT") == 0);
    CHECK(strcmp(vlf_status_name(-1), "unknown status") == 0);
    CHECK(strcmp(vlf_last_error_message(), "") == 0);

    /* Opening: null arguments, a missing file, bytes that are not a field. */
    field = (VlfField *)&sentinel;
    CHECK(vlf_open_path(NULL, &field) == VLF_ERR_NULL_ARGUMENT && field == NULL && message_has("`path` is null"));
    CHECK(vlf_open_path(argv[1], NULL) == VLF_ERR_NULL_ARGUMENT && message_has("vlf_open_path: argument `out`"));
    CHECK(vlf_open_path("/nonexistent/dir/scene.vlf", &field) == VLF_ERR_IO && field == NULL &&
          message_has("/nonexistent/dir/scene.vlf"));
    CHECK(vlf_open_path(argv[0], &field) == VLF_ERR_FORMAT && field == NULL && message_has("not a VLF field"));
    CHECK(vlf_open_memory(NULL, 10, &field) == VLF_ERR_NULL_ARGUMENT && field == NULL);
    CHECK(vlf_open_memory(garbage, sizeof garbage, &field) == VLF_ERR_FORMAT && message_has("bad magic"));
    CHECK(vlf_open_memory(garbage, 0, &field) == VLF_ERR_FORMAT && message_has("shorter than"));

    /* The real field, from its path. */
    CHECK(vlf_open_path(argv[1], &field) == VLF_OK && field != NULL);
    if (field == NULL) {
        fprintf(stderr, "cannot open %s: %s\n", argv[1], vlf_last_error_message());
        return 1;
    }
    CHECK(vlf_triangle_count(field, &triangles) == VLF_OK && triangles == expected_triangles);
    CHECK(vlf_triangle_count(field, NULL) == VLF_ERR_NULL_ARGUMENT);
    CHECK(vlf_triangle_count(NULL, &triangles) == VLF_ERR_NULL_ARGUMENT && message_has("`field` is null"));
    CHECK(vlf_content_hash(field, hash) == VLF_OK);
    hex(hash, 32, hash_hex);
    CHECK(strcmp(hash_hex, argv[3]) == 0);
    CHECK(vlf_input_hash(field, input_hash) == VLF_OK && memcmp(hash, input_hash, 32) != 0);
    CHECK(vlf_content_hash(field, NULL) == VLF_ERR_NULL_ARGUMENT);
    CHECK(vlf_bounding_sphere(field, center, &radius) == VLF_OK && radius > 0.0);
    CHECK(vlf_bounding_sphere(field, center, NULL) == VLF_ERR_NULL_ARGUMENT);
    CHECK(vlf_bounding_sphere(field, center, &center[2]) == VLF_ERR_INVALID_ARGUMENT && message_has("overlap"));

    /* Triangles and provenance, in and out of range. */
    CHECK(vlf_triangle(field, 0, vertices) == VLF_OK);
    CHECK(vlf_triangle(field, triangles, vertices) == VLF_ERR_INVALID_ARGUMENT && message_has("out of range"));
    CHECK(vlf_provenance(field, 0, &prov) == VLF_OK && prov.input_len == strlen(argv[4]) &&
          memcmp(prov.input, argv[4], prov.input_len) == 0 && prov.index < triangles);
    {
        /* The triangles are stored in Morton order, not the mesh's: provenance names each face
         * of the mesh (none dropped, none merged) exactly once. */
        unsigned char *seen = calloc(triangles, 1);
        int once = seen != NULL;
        for (uint32_t i = 0; once && i < triangles; i++) {
            once = vlf_provenance(field, i, &prov) == VLF_OK && prov.index < triangles && !seen[prov.index];
            if (once) seen[prov.index] = 1;
        }
        CHECK(once);
        free(seen);
    }
    CHECK(vlf_provenance(field, triangles - 1, &prov) == VLF_OK && prov.kind >= VLF_SOURCE_OBJ &&
          prov.kind <= VLF_SOURCE_PROGRAM);
    CHECK(vlf_provenance(field, triangles, &prov) == VLF_ERR_INVALID_ARGUMENT);
    CHECK(vlf_provenance(field, VLF_NO_PRIM, &prov) == VLF_ERR_INVALID_ARGUMENT);
    CHECK(vlf_provenance(field, 0, NULL) == VLF_ERR_NULL_ARGUMENT);

    /* A ray from the centre hits or misses but always answers; a ray aimed at triangle 0's
     * centroid from outside the sphere hits something no farther than that centroid. */
    CHECK(vlf_closest_hit(field, &ray, &hit) == VLF_OK);
    for (i = 0; i < 3; i++) {
        double c = (vertices[i] + vertices[3 + i] + vertices[6 + i]) / 3.0;
        ray.org[i] = (float)(center[i] + (i == 2 ? 3.0 * radius : 0.0));
        ray.dir[i] = (float)(c - ray.org[i]);
    }
    CHECK(vlf_closest_hit(field, &ray, &hit) == VLF_OK && hit.prim < triangles && hit.t > 0.0f && hit.t <= 1.0001f);
    CHECK(vlf_any_hit(field, &ray, &any) == VLF_OK && any == 1);
    /* The same ray given relative to the field's origin (the scene's centre) finds the same
     * triangle at the same distance, up to the rounding of the moved origin. */
    {
        VlfRay local = ray;
        VlfHit local_hit;
        double origin[3];
        CHECK(vlf_origin(field, origin) == VLF_OK);
        for (i = 0; i < 3; i++) {
            CHECK(fabs(origin[i] - center[i]) <= 1e-9 * (1.0 + radius));
            local.org[i] = (float)((double)ray.org[i] - origin[i]);
        }
        CHECK(vlf_closest_hit_local(field, &local, &local_hit) == VLF_OK && local_hit.prim == hit.prim &&
              fabsf(local_hit.t - hit.t) <= 1e-4f);
        CHECK(vlf_any_hit_local(field, &local, &any) == VLF_OK && any == 1);
        CHECK(vlf_origin(field, NULL) == VLF_ERR_NULL_ARGUMENT && message_has("`origin` is null"));
        CHECK(vlf_closest_hit_local(field, NULL, &local_hit) == VLF_ERR_NULL_ARGUMENT);
        CHECK(vlf_any_hit_local(NULL, &local, &any) == VLF_ERR_NULL_ARGUMENT);
    }
    /* The same ray, reversed, leaves the sphere: a miss, not an error. */
    for (i = 0; i < 3; i++) {
        ray.dir[i] = -ray.dir[i];
    }
    CHECK(vlf_closest_hit(field, &ray, &hit) == VLF_OK && hit.prim == VLF_NO_PRIM && isinf(hit.t) && hit.u == 0.0f);
    CHECK(vlf_any_hit(field, &ray, &any) == VLF_OK && any == 0);
    /* An invalid ray (NaN origin) misses too. */
    ray.org[0] = NAN;
    CHECK(vlf_closest_hit(field, &ray, &hit) == VLF_OK && hit.prim == VLF_NO_PRIM);
    CHECK(vlf_closest_hit(NULL, &ray, &hit) == VLF_ERR_NULL_ARGUMENT);
    CHECK(vlf_closest_hit(field, NULL, &hit) == VLF_ERR_NULL_ARGUMENT && message_has("`ray` is null"));
    CHECK(vlf_closest_hit(field, &ray, NULL) == VLF_ERR_NULL_ARGUMENT && message_has("`hit` is null"));
    CHECK(vlf_any_hit(field, &ray, NULL) == VLF_ERR_NULL_ARGUMENT);
    CHECK(vlf_closest_hit(field, (const VlfRay *)(raw + 1), &hit) == VLF_ERR_INVALID_ARGUMENT &&
          message_has("not aligned"));

    /* Array calls: empty arrays may be NULL; overlapping ones are refused. */
    CHECK(vlf_closest_hits(field, NULL, 0, NULL) == VLF_OK);
    CHECK(vlf_any_hits(field, NULL, 0, NULL) == VLF_OK);
    CHECK(vlf_closest_hits(field, NULL, 1, hits) == VLF_ERR_NULL_ARGUMENT && message_has("`rays` is null"));
    CHECK(vlf_closest_hits(field, &ray, 1, NULL) == VLF_ERR_NULL_ARGUMENT);
    CHECK(vlf_closest_hits(field, (const VlfRay *)hits, 1, hits) == VLF_ERR_INVALID_ARGUMENT &&
          message_has("overlap"));
    CHECK(vlf_any_hits(field, &ray, 1, (uint8_t *)&ray) == VLF_ERR_INVALID_ARGUMENT);
    CHECK(vlf_closest_hits(field, &ray, SIZE_MAX / 8, hits) == VLF_ERR_INVALID_ARGUMENT && message_has("too large"));

    /* The same field from memory: same hash, same answers. */
    bytes = read_all(argv[1], &len);
    CHECK(bytes != NULL);
    if (bytes != NULL) {
        CHECK(vlf_open_memory(bytes, len, &from_memory) == VLF_OK && from_memory != NULL);
        memset(bytes, 0, len); /* it was copied: clobbering our buffer changes nothing */
        free(bytes);
        CHECK(vlf_content_hash(from_memory, hash2) == VLF_OK && memcmp(hash, hash2, 32) == 0);
    }

    /* Many threads on one field at once, each answer the same as the array call's. */
    make_rays(center, radius);
    CHECK(vlf_closest_hits(field, rays, RAY_COUNT, reference) == VLF_OK);
    CHECK(vlf_any_hits(field, rays, RAY_COUNT, reference_any) == VLF_OK);
    {
        size_t hit_count = 0;
        for (i = 0; i < RAY_COUNT; i++) {
            hit_count += reference[i].prim != VLF_NO_PRIM;
            if ((reference[i].prim != VLF_NO_PRIM) != (reference_any[i] != 0)) {
                failed++;
                fprintf(stderr, "ray %lu: closest and any-hit disagree\n", (unsigned long)i);
            }
        }
        CHECK(hit_count > RAY_COUNT / 10 && hit_count < RAY_COUNT);
    }
    {
        enum { THREADS = 4 };
        pthread_t threads[THREADS];
        struct worker workers[THREADS];
        int t;
        vlf_triangle_count(NULL, NULL); /* sets this thread's message */
        for (t = 0; t < THREADS; t++) {
            workers[t].field = (t % 2 == 0 || from_memory == NULL) ? field : from_memory;
            workers[t].mismatches = 0;
            workers[t].own_message_kept = 0;
            CHECK(pthread_create(&threads[t], NULL, trace_worker, &workers[t]) == 0);
        }
        for (t = 0; t < THREADS; t++) {
            CHECK(pthread_join(threads[t], NULL) == 0);
            CHECK(workers[t].mismatches == 0);
            CHECK(workers[t].own_message_kept);
        }
        /* The workers' failures did not touch this thread's message. */
        CHECK(message_has("vlf_triangle_count: argument `field` is null"));
    }

    calls_as_a_thread_exits();
    about_the_field(field, argv);
    scene(argv);
    packed_with_a_cap(argv);

    vlf_close(from_memory);
    vlf_close(field);
    vlf_close(NULL);
    printf("api_test: %d passed, %d failed\n", passed, failed);
    return failed == 0 ? 0 : 1;
}
