// FNV-1a over the exact bits of Real values: the state hashes of the engine (World::StateHash)
// and of the adapters' read-backs. Equal hashes mean bit-identical values, which is what the
// determinism tests and the benchmark labels compare.
#pragma once

#include <cstdint>
#include <cstring>

#include "quadrant/math.h"

namespace quadrant {

class BitHash {
 public:
  void Mix(Real x) {
    unsigned char bytes[sizeof(Real)];
    std::memcpy(bytes, &x, sizeof(Real));
    for (unsigned char b : bytes) {
      h_ ^= b;
      h_ *= 0x100000001b3ull;
    }
  }
  uint64_t Value() const { return h_; }

 private:
  uint64_t h_ = 0xcbf29ce484222325ull;
};

}  // namespace quadrant
