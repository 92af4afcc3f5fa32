#pragma once
// The few Embree 3 calls both scenes (Scene.cpp, scivis/scene/SciVisScene.cpp) make the same way:
// collecting a device error, a single ray, a closest hit, a packet of 16 closest hits and an
// occlusion test.
#include <embree3/rtcore.h>

#include <string>

#include "renderers/Math.h"

namespace renderers::embree {

// An RTCErrorFunction that keeps the first error's text in the std::string* it is given.
inline void keepFirstError(void* message, RTCError code, const char* text) {
  if (code == RTC_ERROR_NONE) return;
  auto* m = static_cast<std::string*>(message);
  if (m->empty()) *m = text ? text : "unknown error";
}

inline RTCRay ray(Vec3 o, Vec3 d, float tNear, float tFar) {
  RTCRay r;
  r.org_x = o.x, r.org_y = o.y, r.org_z = o.z, r.tnear = tNear;
  r.dir_x = d.x, r.dir_y = d.y, r.dir_z = d.z, r.time = 0;
  r.tfar = tFar, r.mask = 0xFFFFFFFFu, r.id = 0, r.flags = 0;
  return r;
}

// The closest hit in `scene` (geomID RTC_INVALID_GEOMETRY_ID when none).
inline RTCRayHit closestHit(RTCScene scene, Vec3 o, Vec3 d, float tNear, float tFar) {
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  RTCRayHit rh;
  rh.ray = ray(o, d, tNear, tFar);
  rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
  rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
  rtcIntersect1(scene, &context, &rh);
  return rh;
}

// Lane `i` of a 16-ray packet: origin o, direction d over [tNear, tFar], no hit yet.
inline void setLane(RTCRayHit16& rh, int i, Vec3 o, Vec3 d, float tNear, float tFar) {
  rh.ray.org_x[i] = o.x, rh.ray.org_y[i] = o.y, rh.ray.org_z[i] = o.z, rh.ray.tnear[i] = tNear;
  rh.ray.dir_x[i] = d.x, rh.ray.dir_y[i] = d.y, rh.ray.dir_z[i] = d.z, rh.ray.time[i] = 0;
  rh.ray.tfar[i] = tFar, rh.ray.mask[i] = 0xFFFFFFFFu, rh.ray.id[i] = 0, rh.ray.flags[i] = 0;
  rh.hit.geomID[i] = RTC_INVALID_GEOMETRY_ID;
  rh.hit.instID[0][i] = RTC_INVALID_GEOMETRY_ID;
}

// The closest hits of the lanes whose valid[i] is -1, in `rh` (filled with setLane). Not
// RTC_INTERSECT_CONTEXT_FLAG_COHERENT: Embree's frustum traversal for coherent packets breaks
// ties on shared edges differently from single rays, and even lets rays through edges that single
// rays hit (PacketTest's tie test fails with it): packets must hit what single rays hit.
inline void closestHits16(RTCScene scene, const int* valid, RTCRayHit16& rh) {
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  rtcIntersect16(valid, scene, &context, &rh);
}

inline bool occluded(RTCScene scene, Vec3 o, Vec3 d, float tNear, float tFar) {
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  RTCRay r = ray(o, d, tNear, tFar);
  rtcOccluded1(scene, &context, &r);
  return r.tfar < 0;  // Embree sets tfar to -inf on a hit
}

}  // namespace renderers::embree
