// The state hash: FNV-1a over the exact bits of every body's state, in body order.
#include <cstring>

#include "world_internal.h"

namespace quadrant {

uint64_t HashBodies(const Bodies& bodies) {
  uint64_t h = 0xcbf29ce484222325ull;
  auto mix = [&h](Real x) {
    unsigned char bytes[sizeof(Real)];
    std::memcpy(bytes, &x, sizeof(Real));
    for (unsigned char b : bytes) {
      h ^= b;
      h *= 0x100000001b3ull;
    }
  };
  for (int i = 0; i < bodies.Count(); ++i) {
    mix(bodies.xf[i].p.x);
    mix(bodies.xf[i].p.y);
    mix(bodies.xf[i].q.c);
    mix(bodies.xf[i].q.s);
    mix(bodies.vel[i].v.x);
    mix(bodies.vel[i].v.y);
    mix(bodies.vel[i].w);
  }
  return h;
}

}  // namespace quadrant
