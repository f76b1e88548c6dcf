/* The Embree 3 side of `vlf-bench dynamic`: two-level instancing. One triangle mesh in a scene of
 * its own (one BVH, default flags and quality), placed `n` times by instance geometries in a top
 * scene built with the flags Embree recommends for scenes rebuilt every frame
 * (RTC_SCENE_FLAG_DYNAMIC, RTC_BUILD_QUALITY_LOW). Moving instances is rtcSetGeometryTransform,
 * rtcCommitGeometry on each, then rtcCommitScene on the top scene (a top-level rebuild). The Rust
 * side (src/dynamic/embree.rs) owns the handle.
 *
 * Rays arrive as vlf_geom::Ray, 32 bytes: org[3], tmin, dir[3], tmax (formats/rays.md). */

#include <embree3/rtcore.h>
#include <stdint.h>
#include <stdlib.h>

typedef struct {
    RTCDevice device;
    RTCScene mesh;
    RTCScene top;
    unsigned count;
} vlf_embree_inst;

typedef struct {
    float org[3];
    float tmin;
    float dir[3];
    float tmax;
} vlf_inst_ray;

/* The mesh of `count` triangles (9 floats each, an unindexed soup) in a committed scene, and a
 * top scene of `instances` instances of it with identity transforms (not committed: set the
 * transforms, then call vlf_embree_inst_commit). NULL if Embree refuses. */
vlf_embree_inst *vlf_embree_inst_new(const float *triangles, size_t count, unsigned instances) {
    vlf_embree_inst *e = (vlf_embree_inst *)calloc(1, sizeof(vlf_embree_inst));
    if (!e) return NULL;
    e->device = rtcNewDevice(NULL);
    if (!e->device) {
        free(e);
        return NULL;
    }
    RTCGeometry g = rtcNewGeometry(e->device, RTC_GEOMETRY_TYPE_TRIANGLE);
    float *v = (float *)rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), 3 * count);
    unsigned *ix = (unsigned *)rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(unsigned), count);
    if (!v || !ix) {
        rtcReleaseGeometry(g);
        rtcReleaseDevice(e->device);
        free(e);
        return NULL;
    }
    for (size_t i = 0; i < 9 * count; i++) v[i] = triangles[i];
    for (size_t i = 0; i < 3 * count; i++) ix[i] = (unsigned)i;
    rtcCommitGeometry(g);
    e->mesh = rtcNewScene(e->device);
    rtcAttachGeometry(e->mesh, g);
    rtcReleaseGeometry(g);
    rtcCommitScene(e->mesh);
    e->top = rtcNewScene(e->device);
    rtcSetSceneFlags(e->top, RTC_SCENE_FLAG_DYNAMIC);
    rtcSetSceneBuildQuality(e->top, RTC_BUILD_QUALITY_LOW);
    const float identity[12] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0};
    for (unsigned i = 0; i < instances; i++) {
        RTCGeometry inst = rtcNewGeometry(e->device, RTC_GEOMETRY_TYPE_INSTANCE);
        rtcSetGeometryInstancedScene(inst, e->mesh);
        rtcSetGeometryTransform(inst, 0, RTC_FORMAT_FLOAT3X4_ROW_MAJOR, identity);
        rtcCommitGeometry(inst);
        rtcAttachGeometryByID(e->top, inst, i);
        rtcReleaseGeometry(inst);
    }
    e->count = instances;
    return e;
}

/* Instance `i`'s transform: 12 floats, the rows of [A | b], mapping the mesh to the world. */
void vlf_embree_inst_set(vlf_embree_inst *e, unsigned i, const float *rows) {
    RTCGeometry inst = rtcGetGeometry(e->top, i);
    rtcSetGeometryTransform(inst, 0, RTC_FORMAT_FLOAT3X4_ROW_MAJOR, rows);
    rtcCommitGeometry(inst);
}

/* Rebuilds the top level over the instances' current transforms; rtcGetDeviceError's code. */
int vlf_embree_inst_commit(vlf_embree_inst *e) {
    rtcCommitScene(e->top);
    return (int)rtcGetDeviceError(e->device);
}

/* rtcIntersect1 on the top scene: 1 and the hit's t, instance and triangle on a hit, 0 on a miss. */
int vlf_embree_inst_intersect1(const vlf_embree_inst *e, const vlf_inst_ray *r, float *t, unsigned *inst, unsigned *prim) {
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
    rtcIntersect1(e->top, &context, &rh);
    if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return 0;
    *t = rh.ray.tfar;
    *inst = rh.hit.instID[0];
    *prim = rh.hit.primID;
    return 1;
}

/* rtcOccluded1 on the top scene: 1 if anything lies on [tmin, tmax]. */
int vlf_embree_inst_occluded1(const vlf_embree_inst *e, const vlf_inst_ray *r) {
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
    rtcOccluded1(e->top, &context, &ray);
    return ray.tfar == -__builtin_inff();
}

void vlf_embree_inst_free(vlf_embree_inst *e) {
    if (!e) return;
    if (e->top) rtcReleaseScene(e->top);
    if (e->mesh) rtcReleaseScene(e->mesh);
    rtcReleaseDevice(e->device);
    free(e);
}
