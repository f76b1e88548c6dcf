/*
 * The C API's all-hits and hit-count calls from C. Run by tests/c_programs.rs as
 *
 *   all_hits_test FIELD RAYS MAX_HITS OUT
 *
 * RAYS is a rays file (formats/rays.md: 32-byte records). For every ray, the program asks
 * vlf_all_hits with room for every hit, and checks against it: vlf_hit_count, vlf_hit_counts,
 * vlf_all_hits with capacity MAX_HITS (the same first hits), vlf_all_hits_batch with MAX_HITS
 * slots per ray (the same as one ray at a time). It writes OUT: per ray, the number of hits as a
 * uint32 and then the hits (16-byte records), which the Rust side compares with the Rust API.
 * It also checks the calls' argument errors. Prints each failed check and a closing
 * "all_hits_test: N passed, N failed" line; exits 0 only if every check passed.
 */

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "vlf.h"

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

/* Room for every hit of one ray: more than any ray of the tests meets. */
#define ROOM 4096

static VlfRay *read_rays(const char *path, size_t *n) {
    FILE *f = fopen(path, "rb");
    long size;
    VlfRay *rays;
    if (f == NULL || fseek(f, 0, SEEK_END) != 0 || (size = ftell(f)) < 0 || fseek(f, 0, SEEK_SET) != 0) {
        return NULL;
    }
    *n = (size_t)size / sizeof(VlfRay);
    rays = malloc(*n * sizeof(VlfRay) + 1);
    if (rays != NULL && fread(rays, sizeof(VlfRay), *n, f) != *n) {
        free(rays);
        rays = NULL;
    }
    fclose(f);
    return rays;
}

static void argument_errors(const VlfField *field, const VlfRay *ray) {
    _Alignas(8) VlfHit hits[4];
    size_t count = 99, counts[2];
    uint32_t n = 99;
    CHECK(vlf_all_hits(NULL, ray, hits, 4, &count) == VLF_ERR_NULL_ARGUMENT && message_has("`field` is null"));
    CHECK(vlf_all_hits(field, NULL, hits, 4, &count) == VLF_ERR_NULL_ARGUMENT && message_has("`ray` is null"));
    CHECK(vlf_all_hits(field, ray, NULL, 4, &count) == VLF_ERR_NULL_ARGUMENT && message_has("`hits` is null"));
    CHECK(vlf_all_hits(field, ray, hits, 4, NULL) == VLF_ERR_NULL_ARGUMENT && message_has("`count` is null"));
    CHECK(vlf_all_hits(field, ray, (VlfHit *)((char *)hits + 1), 2, &count) == VLF_ERR_INVALID_ARGUMENT &&
          message_has("not aligned"));
    CHECK(vlf_all_hits(field, ray, hits, SIZE_MAX / 8, &count) == VLF_ERR_INVALID_ARGUMENT && message_has("too large"));
    CHECK(vlf_all_hits(field, ray, hits, 4, (size_t *)(void *)&hits[1]) == VLF_ERR_INVALID_ARGUMENT &&
          message_has("overlap"));
    CHECK(count == 99);
    /* Capacity 0: nothing asked, nothing written but the count. */
    CHECK(vlf_all_hits(field, ray, NULL, 0, &count) == VLF_OK && count == 0);
    CHECK(vlf_all_hits_batch(field, NULL, 0, 5, NULL, NULL) == VLF_OK);
    CHECK(vlf_all_hits_batch(field, ray, 1, 0, NULL, counts) == VLF_OK && counts[0] == 0);
    CHECK(vlf_all_hits_batch(field, ray, 3, SIZE_MAX / 2, hits, counts) == VLF_ERR_INVALID_ARGUMENT &&
          message_has("too many"));
    CHECK(vlf_all_hits_batch(field, ray, 1, 4, hits, NULL) == VLF_ERR_NULL_ARGUMENT && message_has("`counts` is null"));
    CHECK(vlf_all_hits_batch(field, ray, 1, 4, hits, (size_t *)(void *)hits) == VLF_ERR_INVALID_ARGUMENT &&
          message_has("`hits` and `counts` overlap"));
    CHECK(vlf_hit_count(field, NULL, &n) == VLF_ERR_NULL_ARGUMENT && n == 99);
    CHECK(vlf_hit_count(field, ray, NULL) == VLF_ERR_NULL_ARGUMENT);
    CHECK(vlf_hit_counts(field, NULL, 0, NULL) == VLF_OK);
    CHECK(vlf_hit_counts(field, ray, 1, (uint32_t *)(void *)ray) == VLF_ERR_INVALID_ARGUMENT &&
          message_has("overlap"));
    CHECK(vlf_hit_counts(field, ray, SIZE_MAX / 16, &n) == VLF_ERR_INVALID_ARGUMENT && message_has("too large"));
}

int main(int argc, char **argv) {
    VlfField *field = NULL;
    VlfRay *rays;
    size_t n = 0, i, k, max_hits, total = 0, several = 0;
    VlfHit *all, *batch;
    size_t *batch_counts;
    uint32_t *counts;
    FILE *out;
    if (argc != 5) {
        fprintf(stderr, "usage: all_hits_test FIELD RAYS MAX_HITS OUT\n");
        return 2;
    }
    max_hits = (size_t)strtoul(argv[3], NULL, 10);
    if (vlf_open_path(argv[1], &field) != VLF_OK || (rays = read_rays(argv[2], &n)) == NULL || n == 0) {
        fprintf(stderr, "all_hits_test: %s\n", vlf_last_error_message());
        return 1;
    }
    argument_errors(field, &rays[0]);
    all = malloc(ROOM * sizeof(VlfHit));
    batch = malloc(n * max_hits * sizeof(VlfHit) + 1);
    batch_counts = malloc(n * sizeof(size_t));
    counts = malloc(n * sizeof(uint32_t));
    out = fopen(argv[4], "wb");
    if (all == NULL || batch == NULL || batch_counts == NULL || counts == NULL || out == NULL) {
        fprintf(stderr, "all_hits_test: out of memory or cannot write %s\n", argv[4]);
        return 1;
    }
    CHECK(vlf_hit_counts(field, rays, n, counts) == VLF_OK);
    CHECK(vlf_all_hits_batch(field, rays, n, max_hits, batch, batch_counts) == VLF_OK);
    for (i = 0; i < n; i++) {
        size_t count = 0, first = 0;
        uint32_t one = 0, count32;
        VlfHit few[64];
        int ok = vlf_all_hits(field, &rays[i], all, ROOM, &count) == VLF_OK && count < ROOM;
        ok = ok && vlf_hit_count(field, &rays[i], &one) == VLF_OK && one == count && counts[i] == count;
        /* In order of t, then id. */
        for (k = 1; ok && k < count; k++) {
            ok = all[k - 1].t < all[k].t || (all[k - 1].t == all[k].t && all[k - 1].prim < all[k].prim);
        }
        /* The first max_hits: the same one at a time and in the batch. */
        ok = ok && max_hits <= 64 && vlf_all_hits(field, &rays[i], few, max_hits, &first) == VLF_OK;
        ok = ok && first == (count < max_hits ? count : max_hits) && batch_counts[i] == first;
        ok = ok && memcmp(few, all, first * sizeof(VlfHit)) == 0;
        ok = ok && memcmp(&batch[i * max_hits], all, first * sizeof(VlfHit)) == 0;
        if (!ok) {
            failed++;
            fprintf(stderr, "ray %zu: %zu hits, count %u, batch count %u, first %zu, batch first %zu\n", i, count,
                    (unsigned)one, (unsigned)counts[i], first, batch_counts[i]);
        } else {
            passed++;
        }
        count32 = (uint32_t)count;
        fwrite(&count32, sizeof count32, 1, out);
        fwrite(all, sizeof(VlfHit), count, out);
        total += count;
        several += count > 1;
    }
    fclose(out);
    printf("all_hits_test: %zu rays, %zu hits, %zu rays with several\n", n, total, several);
    printf("all_hits_test: %d passed, %d failed\n", passed, failed);
    free(all);
    free(batch);
    free(batch_counts);
    free(counts);
    free(rays);
    vlf_close(field);
    return failed == 0 ? 0 : 1;
}
