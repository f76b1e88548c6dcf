/*
 * The dynamic-scene C API from C: a field placed twice (once mirrored and scaled), traced; then
 * moved, masked, edited (triangles removed and inserted) and traced again; and the errors of each
 * call. Run by tests/c_programs.rs as
 *
 *   scene_test FIELD RAYS HITS_BEFORE HITS_AFTER
 *
 * RAYS a rays file (formats/rays.md). Writes, for every ray, its closest hit (16 bytes), its
 * instance (4 bytes) and its any-hit byte, for the scene before the edits to HITS_BEFORE and after
 * them to HITS_AFTER, for the Rust side to hold against the Rust API bit for bit. Prints each
 * failed check and a closing "scene_test: N passed, N failed" line; exits 0 only if every check
 * passed.
 */

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "vlf.h"

_Static_assert(VLF_NO_INSTANCE == 0xFFFFFFFFu, "the instance of a miss");

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

static int message_has(const char *part) { return strstr(vlf_last_error_message(), part) != NULL; }

/* Traces every ray closest-hit (all instances) and any-hit (mask `any_mask`) and writes the
 * records to `path`. */
static void trace(const VlfScene *scene, const VlfRay *rays, size_t n, uint32_t any_mask, const char *path) {
    VlfHit *hits = malloc(n * sizeof *hits);
    uint32_t *instances = malloc(n * sizeof *instances);
    uint8_t *any = malloc(n);
    CHECK(hits && instances && any);
    if (!hits || !instances || !any) exit(1);
    CHECK(vlf_scene_closest_hits(scene, rays, n, 0xFFFFFFFFu, hits, instances) == VLF_OK);
    for (size_t i = 0; i < n; i++) {
        VlfHit one;
        uint32_t instance;
        /* One at a time: the same answer as the batch. */
        if (i % 97 == 0) {
            CHECK(vlf_scene_closest_hit(scene, &rays[i], 0xFFFFFFFFu, &one, &instance) == VLF_OK);
            CHECK(memcmp(&one, &hits[i], sizeof one) == 0 && instance == instances[i]);
        }
        CHECK(vlf_scene_any_hit(scene, &rays[i], any_mask, &any[i]) == VLF_OK);
    }
    FILE *f = fopen(path, "wb");
    CHECK(f != NULL);
    if (!f) exit(1);
    for (size_t i = 0; i < n; i++) {
        fwrite(&hits[i], sizeof hits[i], 1, f);
        fwrite(&instances[i], sizeof instances[i], 1, f);
        fwrite(&any[i], 1, 1, f);
    }
    fclose(f);
    free(hits);
    free(instances);
    free(any);
}

int main(int argc, char **argv) {
    if (argc != 5) {
        fprintf(stderr, "usage: scene_test FIELD RAYS HITS_BEFORE HITS_AFTER\n");
        return 2;
    }
    /* The rays. */
    FILE *f = fopen(argv[2], "rb");
    if (!f) return 1;
    fseek(f, 0, SEEK_END);
    size_t n = (size_t)ftell(f) / sizeof(VlfRay);
    fseek(f, 0, SEEK_SET);
    VlfRay *rays = malloc(n * sizeof *rays);
    if (!rays || fread(rays, sizeof *rays, n, f) != n) return 1;
    fclose(f);
    /* The field's sphere and triangle count, through the field API. */
    VlfField *field = NULL;
    double c[3], r;
    uint32_t count;
    CHECK(vlf_open_path(argv[1], &field) == VLF_OK);
    CHECK(vlf_bounding_sphere(field, c, &r) == VLF_OK && vlf_triangle_count(field, &count) == VLF_OK);
    vlf_close(field);

    VlfScene *scene = NULL;
    CHECK(vlf_scene_create(&scene) == VLF_OK && scene != NULL);
    uint32_t id = 99, a = 99, b = 99, bad = 99;
    CHECK(vlf_scene_add_field(scene, argv[1], &id) == VLF_OK && id == 0);
    CHECK(vlf_scene_add_field(scene, "/nonexistent/field.vlf", &bad) == VLF_ERR_IO && bad == 99);
    CHECK(message_has("vlf_scene_add_field") && message_has("/nonexistent/field.vlf"));
    /* Instance 0 where the field was baked; instance 1 mirrored in x, stretched and moved. */
    const double mirror[16] = {-2, 0, 0, 3 * r, 0, 1, 0, 0, 0, 0, 0.5, 0, 0, 0, 0, 1};
    CHECK(vlf_scene_add_instance(scene, id, NULL, 1, &a) == VLF_OK && a == 0);
    CHECK(vlf_scene_add_instance(scene, id, mirror, 2, &b) == VLF_OK && b == 1);
    /* Refused transforms and ids, each named. */
    const double singular[16] = {1, 0, 0, 0, 0, 0, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
    const double projective[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 1, 1};
    CHECK(vlf_scene_add_instance(scene, id, singular, 1, &bad) == VLF_ERR_INVALID_ARGUMENT && message_has("singular"));
    CHECK(vlf_scene_set_transform(scene, a, projective) == VLF_ERR_INVALID_ARGUMENT && message_has("last row"));
    CHECK(vlf_scene_add_instance(scene, 7, NULL, 1, &bad) == VLF_ERR_INVALID_ARGUMENT && message_has("no field 7"));
    CHECK(vlf_scene_set_transform(scene, 9, NULL) == VLF_ERR_INVALID_ARGUMENT && message_has("no instance 9"));
    CHECK(vlf_scene_add_instance(NULL, id, NULL, 1, &bad) == VLF_ERR_NULL_ARGUMENT && message_has("`scene`"));
    CHECK(vlf_scene_closest_hit(scene, NULL, 1, NULL, NULL) == VLF_ERR_NULL_ARGUMENT);
    CHECK(bad == 99);
    uint32_t live = 0;
    CHECK(vlf_scene_instance_count(scene, &live) == VLF_OK && live == 2);

    trace(scene, rays, n, 2, argv[3]);

    /* The same two instances placed in one call answer every ray as the two calls above do. */
    VlfScene *batch = NULL;
    uint32_t batch_field = 99, batch_first = 99;
    CHECK(vlf_scene_create(&batch) == VLF_OK && vlf_scene_add_field(batch, argv[1], &batch_field) == VLF_OK);
    const VlfInstanceDesc pair[2] = {{batch_field, 1, NULL}, {batch_field, 2, mirror}};
    CHECK(vlf_scene_add_instances(batch, pair, 2, &batch_first) == VLF_OK && batch_first == 0);
    for (size_t i = 0; i < n; i++) {
        VlfHit h1, h2;
        uint32_t i1, i2;
        CHECK(vlf_scene_closest_hit(scene, &rays[i], 0xFFFFFFFFu, &h1, &i1) == VLF_OK);
        CHECK(vlf_scene_closest_hit(batch, &rays[i], 0xFFFFFFFFu, &h2, &i2) == VLF_OK);
        if (memcmp(&h1, &h2, sizeof h1) != 0 || i1 != i2) {
            CHECK(!"a batch-placed instance answers as one placed alone");
            break;
        }
    }
    /* A bad field id or transform, second of three, is named and nothing is placed. */
    const VlfInstanceDesc no_field[3] = {{batch_field, 1, NULL}, {7, 1, NULL}, {batch_field, 1, NULL}};
    CHECK(vlf_scene_add_instances(batch, no_field, 3, &batch_first) == VLF_ERR_INVALID_ARGUMENT);
    CHECK(message_has("instances[1]") && message_has("no field 7") && batch_first == 0);
    const VlfInstanceDesc squashed[3] = {{batch_field, 1, NULL}, {batch_field, 1, singular}, {batch_field, 1, NULL}};
    CHECK(vlf_scene_add_instances(batch, squashed, 3, NULL) == VLF_ERR_INVALID_ARGUMENT);
    CHECK(message_has("instances[1].transform") && message_has("singular"));
    CHECK(vlf_scene_instance_count(batch, &live) == VLF_OK && live == 2);
    CHECK(vlf_scene_add_instances(batch, NULL, 1, NULL) == VLF_ERR_NULL_ARGUMENT);
    CHECK(vlf_scene_add_instances(batch, NULL, 0, &batch_first) == VLF_OK && batch_first == 2);
    vlf_scene_destroy(batch);

    /* Move instance 0 up by r/2, show instance 1 to mask 3, and edit the field: both see it. */
    const double up[16] = {1, 0, 0, 0, 0, 1, 0, 0.5 * r, 0, 0, 1, 0, 0, 0, 0, 1};
    CHECK(vlf_scene_set_transform(scene, a, up) == VLF_OK);
    CHECK(vlf_scene_set_mask(scene, b, 3) == VLF_OK);
    const uint32_t ids[3] = {0, 1, 1};
    uint64_t removed = 0, storage[2] = {0, 0};
    /* A misaligned `removed` fails before anything is removed: the next call still removes two. */
    uint64_t *misaligned = (uint64_t *)(void *)((char *)storage + 1);
    CHECK(vlf_scene_remove_triangles(scene, id, ids, 3, misaligned) == VLF_ERR_INVALID_ARGUMENT &&
          message_has("not aligned"));
    CHECK(vlf_scene_remove_object(scene, id, "nothing", misaligned) == VLF_ERR_INVALID_ARGUMENT &&
          message_has("not aligned"));
    CHECK(vlf_scene_remove_triangles(scene, id, ids, 3, &removed) == VLF_OK && removed == 2);
    const uint32_t out_of_range[1] = {count + 5};
    CHECK(vlf_scene_remove_triangles(scene, id, out_of_range, 1, NULL) == VLF_ERR_INVALID_ARGUMENT);
    CHECK(message_has("out of range"));
    CHECK(vlf_scene_remove_object(scene, id, "nothing", &removed) == VLF_ERR_INVALID_ARGUMENT);
    CHECK(message_has("\"nothing\""));
    /* Two triangles near the centre, the second placed by a transform (a quarter of the way up). */
    const double tris[18] = {
        c[0], c[1], c[2], c[0] + 0.5 * r, c[1], c[2], c[0], c[1] + 0.5 * r, c[2],
        c[0], c[1], c[2] + 0.25 * r, c[0] + 0.25 * r, c[1], c[2] + 0.25 * r, c[0], c[1] + 0.25 * r, c[2] + 0.5 * r,
    };
    const double lift[16] = {1, 0, 0, 0, 0, 1, 0, 0.25 * r, 0, 0, 1, 0, 0, 0, 0, 1};
    uint32_t first = 0;
    CHECK(vlf_scene_insert_triangles(scene, id, tris, 1, NULL, &first) == VLF_OK && first == count);
    CHECK(vlf_scene_insert_triangles(scene, id, tris + 9, 1, lift, &first) == VLF_OK && first == count + 1);
    const double far[9] = {c[0] + 10 * r, c[1], c[2], c[0] + 11 * r, c[1], c[2], c[0] + 10 * r, c[1] + r, c[2]};
    CHECK(vlf_scene_insert_triangles(scene, id, far, 1, NULL, &first) == VLF_ERR_INVALID_ARGUMENT);
    CHECK(message_has("bounding sphere") && first == count + 1);
    /* Several meshes in one call, each with its own transform: zero-area triangles (kept, never
     * hit), so the traces below do not change. A failing mesh inserts nothing of any mesh. */
    const double flat[27] = {
        c[0], c[1], c[2], c[0] + 0.5 * r, c[1], c[2], c[0] + 0.25 * r, c[1], c[2],
        c[0], c[1], c[2], c[0], c[1] + 0.5 * r, c[2], c[0], c[1] + 0.25 * r, c[2],
        c[0], c[1], c[2], c[0], c[1], c[2] + 0.5 * r, c[0], c[1], c[2] + 0.25 * r,
    };
    const VlfMesh meshes[2] = {{flat, 2, NULL}, {flat + 18, 1, lift}};
    uint32_t firsts[2] = {0, 0};
    CHECK(vlf_scene_insert_meshes(scene, id, meshes, 2, firsts) == VLF_OK);
    CHECK(firsts[0] == count + 2 && firsts[1] == count + 4);
    const VlfMesh with_far[2] = {{flat, 2, NULL}, {far, 1, NULL}};
    CHECK(vlf_scene_insert_meshes(scene, id, with_far, 2, firsts) == VLF_ERR_INVALID_ARGUMENT);
    CHECK(message_has("meshes[1]: ") && message_has("bounding sphere") && firsts[0] == count + 2);
    const VlfMesh with_singular[1] = {{flat, 1, singular}};
    CHECK(vlf_scene_insert_meshes(scene, id, with_singular, 1, firsts) == VLF_ERR_INVALID_ARGUMENT);
    CHECK(message_has("meshes[0].transform") && message_has("singular"));
    const VlfMesh without_vertices[1] = {{NULL, 1, NULL}};
    CHECK(vlf_scene_insert_meshes(scene, id, without_vertices, 1, NULL) == VLF_ERR_NULL_ARGUMENT);
    CHECK(vlf_scene_insert_meshes(scene, 7, meshes, 2, NULL) == VLF_ERR_INVALID_ARGUMENT && message_has("no field 7"));
    CHECK(vlf_scene_insert_meshes(scene, id, NULL, 0, NULL) == VLF_OK);
    CHECK(vlf_scene_insert_meshes(scene, id, meshes + 1, 1, firsts) == VLF_OK && firsts[0] == count + 5);

    trace(scene, rays, n, 1, argv[4]);

    CHECK(vlf_scene_remove_instance(scene, b) == VLF_OK);
    CHECK(vlf_scene_remove_instance(scene, b) == VLF_ERR_INVALID_ARGUMENT);
    CHECK(vlf_scene_instance_count(scene, &live) == VLF_OK && live == 1);
    vlf_scene_destroy(scene);
    vlf_scene_destroy(NULL);
    free(rays);
    printf("scene_test: %d passed, %d failed\n", passed, failed);
    return failed == 0 ? 0 : 1;
}
