/*
 * trace_rays: trace a rays file through a visibility field with the VLF C API.
 *
 *   trace_rays [--memory] [--single] FIELD RAYS HITS [ANY]
 *
 * RAYS is a rays file and HITS receives a hits file, as `vlf-bake rays` and `vlf-bake trace`
 * write them (formats/rays.md): headerless arrays of 32-byte rays and 16-byte hits, which are
 * exactly VlfRay and VlfHit in memory. ANY, if given, receives one byte per ray: 1 if the ray
 * hits anything, 0 if not. The program prints the field's size and content hash, counts of
 * hits, and where the first hit triangle came from.
 *
 *   --memory  read FIELD into memory and open it with vlf_open_memory (default: vlf_open_path,
 *             which maps the file)
 *   --single  trace ray by ray with vlf_closest_hit and vlf_any_hit (default: the array calls
 *             vlf_closest_hits and vlf_any_hits)
 *
 * Exit status: 0 on success, 1 on a failure (one line on standard error), 2 on a bad command line.
 * Records are read and written in the host's byte order; the files are little-endian, as are
 * all the targets the library builds for.
 *
 * Build (docs/c-api.md):
 *   cargo build --release -p vlf-capi
 *   cc -std=c99 -O2 -I crates/vlf-capi/include crates/vlf-capi/examples/trace_rays.c \
 *      target/release/libvlf.a -lpthread -ldl -lm -o trace_rays
 */

#include <inttypes.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "vlf.h"

/* Reads a whole file into a new buffer; returns NULL (with a message) on failure. */
static void *read_file(const char *path, size_t *len) {
    FILE *f = fopen(path, "rb");
    void *data = NULL;
    long size;
    if (f == NULL) {
        perror(path);
        return NULL;
    }
    if (fseek(f, 0, SEEK_END) != 0 || (size = ftell(f)) < 0 || fseek(f, 0, SEEK_SET) != 0) {
        perror(path);
        fclose(f);
        return NULL;
    }
    /* One extra byte so that an empty file still gets a non-NULL buffer. */
    data = malloc((size_t)size + 1);
    if (data == NULL) {
        fprintf(stderr, "%s: out of memory for %ld bytes\n", path, size);
    } else if (fread(data, 1, (size_t)size, f) != (size_t)size) {
        fprintf(stderr, "%s: read error\n", path);
        free(data);
        data = NULL;
    }
    fclose(f);
    *len = (size_t)size;
    return data;
}

static int write_file(const char *path, const void *data, size_t len) {
    FILE *f = fopen(path, "wb");
    if (f == NULL || fwrite(data, 1, len, f) != len || fclose(f) != 0) {
        perror(path);
        return 0;
    }
    return 1;
}

/* Reports a failed VLF call with the library's message. */
static int vlf_failed(const char *what, VlfStatus status) {
    fprintf(stderr, "trace_rays: %s failed (%s): %s\n", what, vlf_status_name(status), vlf_last_error_message());
    return 1;
}

static int usage(void) {
    fprintf(stderr, "usage: trace_rays [--memory] [--single] FIELD RAYS HITS [ANY]\n");
    return 2;
}

int main(int argc, char **argv) {
    int memory = 0, single = 0, argi = 1, result = 1;
    const char *field_path, *rays_path, *hits_path, *any_path;
    VlfField *field = NULL;
    VlfStatus status;
    VlfRay *rays = NULL;
    VlfHit *hits = NULL;
    uint8_t *any = NULL;
    void *field_bytes = NULL;
    size_t rays_len = 0, n, i, closest_count = 0, any_count = 0, first = (size_t)-1;
    uint32_t triangles;
    uint8_t hash[32];

    for (; argi < argc && strncmp(argv[argi], "--", 2) == 0; argi++) {
        if (strcmp(argv[argi], "--memory") == 0) {
            memory = 1;
        } else if (strcmp(argv[argi], "--single") == 0) {
            single = 1;
        } else {
            return usage();
        }
    }
    if (argc - argi != 3 && argc - argi != 4) {
        return usage();
    }
    field_path = argv[argi];
    rays_path = argv[argi + 1];
    hits_path = argv[argi + 2];
    any_path = argc - argi == 4 ? argv[argi + 3] : NULL;

    if (memory) {
        size_t len = 0;
        field_bytes = read_file(field_path, &len);
        if (field_bytes == NULL) {
            goto done;
        }
        status = vlf_open_memory(field_bytes, len, &field);
        /* The library copied the bytes: ours can go now. */
        free(field_bytes);
    } else {
        status = vlf_open_path(field_path, &field);
    }
    if (status != VLF_OK) {
        result = vlf_failed("opening the field", status);
        goto done;
    }

    rays = read_file(rays_path, &rays_len);
    if (rays == NULL) {
        goto done;
    }
    if (rays_len % sizeof(VlfRay) != 0) {
        fprintf(stderr, "trace_rays: %s is %lu bytes, not a multiple of %lu: not a rays file\n", rays_path,
                (unsigned long)rays_len, (unsigned long)sizeof(VlfRay));
        goto done;
    }
    n = rays_len / sizeof(VlfRay);
    hits = malloc(n * sizeof(VlfHit) + 1);
    any = malloc(n + 1);
    if (hits == NULL || any == NULL) {
        fprintf(stderr, "trace_rays: out of memory for %lu rays\n", (unsigned long)n);
        goto done;
    }

    if (single) {
        for (i = 0; i < n; i++) {
            if ((status = vlf_closest_hit(field, &rays[i], &hits[i])) != VLF_OK) {
                result = vlf_failed("vlf_closest_hit", status);
                goto done;
            }
            if ((status = vlf_any_hit(field, &rays[i], &any[i])) != VLF_OK) {
                result = vlf_failed("vlf_any_hit", status);
                goto done;
            }
        }
    } else {
        if ((status = vlf_closest_hits(field, rays, n, hits)) != VLF_OK) {
            result = vlf_failed("vlf_closest_hits", status);
            goto done;
        }
        if ((status = vlf_any_hits(field, rays, n, any)) != VLF_OK) {
            result = vlf_failed("vlf_any_hits", status);
            goto done;
        }
    }

    for (i = 0; i < n; i++) {
        if (hits[i].prim != VLF_NO_PRIM) {
            closest_count++;
            if (first == (size_t)-1) {
                first = i;
            }
        }
        any_count += any[i] != 0;
    }
    if (!write_file(hits_path, hits, n * sizeof(VlfHit)) || (any_path != NULL && !write_file(any_path, any, n))) {
        goto done;
    }

    if ((status = vlf_triangle_count(field, &triangles)) != VLF_OK) {
        result = vlf_failed("vlf_triangle_count", status);
        goto done;
    }
    if ((status = vlf_content_hash(field, hash)) != VLF_OK) {
        result = vlf_failed("vlf_content_hash", status);
        goto done;
    }
    printf("field: %" PRIu32 " triangles, content hash ", triangles);
    for (i = 0; i < sizeof hash; i++) {
        printf("%02x", hash[i]);
    }
    printf("\nrays: %lu, closest hits: %lu, any hits: %lu\n", (unsigned long)n, (unsigned long)closest_count,
           (unsigned long)any_count);
    if (first != (size_t)-1) {
        VlfProvenance p;
        const VlfHit *h = &hits[first];
        if ((status = vlf_provenance(field, h->prim, &p)) != VLF_OK) {
            result = vlf_failed("vlf_provenance", status);
            goto done;
        }
        /* Provenance strings are not NUL-terminated: print them with their lengths. */
        printf("first hit: ray %lu, t = %.9g, triangle %" PRIu32 " = triangle %" PRIu32 " of \"%.*s\" in %.*s\n", (unsigned long)first,
               (double)h->t, h->prim, p.index, (int)p.name_len, p.name, (int)p.input_len, p.input);
    }
    result = 0;

done:
    free(rays);
    free(hits);
    free(any);
    vlf_close(field);
    return result;
}
