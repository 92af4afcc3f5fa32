#pragma once
// The few Embree 3 calls both scenes (Scene.cpp, scivis/SciVisScene.cpp) make the same way:
// collecting a device error, a single ray, a closest hit and an occlusion test.
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

inline bool occluded(RTCScene scene, Vec3 o, Vec3 d, float tNear, float tFar) {
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  RTCRay r = ray(o, d, tNear, tFar);
  rtcOccluded1(scene, &context, &r);
  return r.tfar < 0;  // Embree sets tfar to -inf on a hit
}

}  // namespace renderers::embree
