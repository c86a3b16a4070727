// The state hash: FNV-1a over the exact bits of every body's state, in body order.
#include "quadrant/bit_hash.h"
#include "world/world_internal.h"

namespace quadrant {

uint64_t HashBodies(const Bodies& bodies) {
  BitHash h;
  auto mix = [&h](Real x) { h.Mix(x); };
  for (int i = 0; i < bodies.Count(); ++i) {
    mix(bodies.xf[i].p.x);
    mix(bodies.xf[i].p.y);
    mix(bodies.xf[i].q.c);
    mix(bodies.xf[i].q.s);
    mix(bodies.vel[i].v.x);
    mix(bodies.vel[i].v.y);
    mix(bodies.vel[i].w);
  }
  return h.Value();
}

}  // namespace quadrant
