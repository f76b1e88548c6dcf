/* The Embree 3 side of `vlf-bench peers`: a device with a memory monitor, one triangle-mesh scene
 * at the default scene flags and build quality, and single-ray queries (rtcIntersect1 and
 * rtcOccluded1), one ray per call. The Rust side (src/peers/embree.rs) owns the handle.
 *
 * Rays arrive as vlf_geom::Ray, 32 bytes: org[3], tmin, dir[3], tmax (formats/rays.md). */

#include <embree3/rtcore.h>
#include <stdint.h>
#include <stdlib.h>

typedef struct {
    RTCDevice device;
    RTCScene scene;
    /* Bytes Embree holds now and at most, from the memory monitor (updated atomically: the
     * builder allocates from several threads). */
    int64_t bytes;
    int64_t peak;
} vlf_embree;

/* Mirrors vlf_geom::Ray. */
typedef struct {
    float org[3];
    float tmin;
    float dir[3];
    float tmax;
} vlf_ray;

static bool monitor(void *user, ssize_t bytes, bool post) {
    (void)post;
    vlf_embree *e = (vlf_embree *)user;
    int64_t now = __atomic_add_fetch(&e->bytes, (int64_t)bytes, __ATOMIC_RELAXED);
    int64_t peak = __atomic_load_n(&e->peak, __ATOMIC_RELAXED);
    while (now > peak && !__atomic_compare_exchange_n(&e->peak, &peak, now, true, __ATOMIC_RELAXED, __ATOMIC_RELAXED)) {
    }
    return true; /* never refuse an allocation */
}

/* A new device (config as for rtcNewDevice; NULL for the defaults) with the monitor installed.
 * NULL if Embree refuses. */
vlf_embree *vlf_embree_new(const char *config) {
    vlf_embree *e = (vlf_embree *)calloc(1, sizeof(vlf_embree));
    if (!e) return NULL;
    e->device = rtcNewDevice(config);
    if (!e->device) {
        free(e);
        return NULL;
    }
    rtcSetDeviceMemoryMonitorFunction(e->device, monitor, e);
    return e;
}

/* Builds the scene from `count` triangles, 9 floats each (v0, v1, v2), as an unindexed soup:
 * vertex buffer of 3·count float3, index buffer (3i, 3i+1, 3i+2). Returns rtcGetDeviceError's code
 * (0: none). `before_commit` receives the bytes held once the buffers are filled. */
int vlf_embree_build(vlf_embree *e, const float *triangles, size_t count, int64_t *before_commit) {
    RTCGeometry g = rtcNewGeometry(e->device, RTC_GEOMETRY_TYPE_TRIANGLE);
    float *v = (float *)rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), 3 * count);
    unsigned *ix = (unsigned *)rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(unsigned), count);
    if (!v || !ix) {
        rtcReleaseGeometry(g);
        return (int)rtcGetDeviceError(e->device);
    }
    for (size_t i = 0; i < 9 * count; i++) v[i] = triangles[i];
    for (size_t i = 0; i < 3 * count; i++) ix[i] = (unsigned)i;
    rtcCommitGeometry(g);
    e->scene = rtcNewScene(e->device);
    rtcAttachGeometry(e->scene, g);
    rtcReleaseGeometry(g);
    *before_commit = __atomic_load_n(&e->bytes, __ATOMIC_RELAXED);
    rtcCommitScene(e->scene);
    return (int)rtcGetDeviceError(e->device);
}

int64_t vlf_embree_bytes(const vlf_embree *e) { return __atomic_load_n(&e->bytes, __ATOMIC_RELAXED); }
int64_t vlf_embree_peak(const vlf_embree *e) { return __atomic_load_n(&e->peak, __ATOMIC_RELAXED); }

/* rtcIntersect1: 1 and the hit's t, primID, u, v on a hit; 0 on a miss. */
int vlf_embree_intersect1(const vlf_embree *e, const vlf_ray *r, float *t, unsigned *prim, float *u, float *v) {
    struct RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    struct RTCRayHit rh;
    rh.ray.org_x = r->org[0];
    rh.ray.org_y = r->org[1];
    rh.ray.org_z = r->org[2];
    rh.ray.tnear = r->tmin;
    rh.ray.dir_x = r->dir[0];
    rh.ray.dir_y = r->dir[1];
    rh.ray.dir_z = r->dir[2];
    rh.ray.time = 0.0f;
    rh.ray.tfar = r->tmax;
    rh.ray.mask = 0xFFFFFFFFu;
    rh.ray.id = 0;
    rh.ray.flags = 0;
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(e->scene, &context, &rh);
    if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return 0;
    *t = rh.ray.tfar;
    *prim = rh.hit.primID;
    *u = rh.hit.u;
    *v = rh.hit.v;
    return 1;
}

/* rtcOccluded1: 1 if anything lies on [tmin, tmax]. */
int vlf_embree_occluded1(const vlf_embree *e, const vlf_ray *r) {
    struct RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    struct RTCRay ray;
    ray.org_x = r->org[0];
    ray.org_y = r->org[1];
    ray.org_z = r->org[2];
    ray.tnear = r->tmin;
    ray.dir_x = r->dir[0];
    ray.dir_y = r->dir[1];
    ray.dir_z = r->dir[2];
    ray.time = 0.0f;
    ray.tfar = r->tmax;
    ray.mask = 0xFFFFFFFFu;
    ray.id = 0;
    ray.flags = 0;
    rtcOccluded1(e->scene, &context, &ray);
    /* Embree sets tfar to -inf when the ray is occluded. */
    return ray.tfar == -__builtin_inff();
}

void vlf_embree_free(vlf_embree *e) {
    if (!e) return;
    if (e->scene) rtcReleaseScene(e->scene);
    rtcReleaseDevice(e->device);
    free(e);
}
