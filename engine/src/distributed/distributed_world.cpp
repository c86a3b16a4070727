// The distributed world: tiles, ownership, migration, shadows, neighbour rounds and the two
// solvers, the soft step per rank and the split Jacobi solve (quadrant/distributed_world.h gives
// the scheme and its contract).
//
// State between steps: `local`, the World's arrays of the rank's statics, owned bodies and
// shadows, holds the owned bodies' state (ownedStale; ownedLocal names their rows). A Record per
// owned body (what a rank needs to collide, solve and integrate it: the unit of migration,
// shadows and checkpoints) is made from its row where it travels, and `owned` holds them all only
// after Load, a checkpoint or a rebalance, or where they are read whole (SyncOwned). A step keeps
// `local` while no body leaves or arrives and the same shadows come (layoutValid: only the
// shadows' rows and the boxes are written), patches it when a few do (PatchLocal: kept rows stay,
// arrivals and shadows fill the freed rows) and rebuilds it, in id order, from records only when
// tiles change owner or a scene is loaded. Rows need not be in id order: FindContacts orients
// every pair and sorts the contacts by body id, so the arithmetic, and the state hash, is the same
// at any rank count.
//
// Why (circle stress, 16004 circles per rank, amd-epyc-2c; docs/notes/distributed.md has the commands
// and figures): on one rank the step takes 1.1-1.2 ms, 1.1-1.2x the World's default engine;
// rebuilding the arrays from records every step made it 6.3-7.5. On two ranks a body crosses the
// boundary, or the shadows change, nearly every step: rebuilding made the step 2.5-2.8 ms, and
// any pass over every body every step shows (the owned list's merge, 85 instructions a body, and
// the patch's passes over every row were 2.4M of a 15.3M-instruction step): the patch, the
// merge and the shadows' pass visit what changed, the tiles are dealt in bisection order (at 2
// ranks two halves; Morton order gave a corner and an L, a 45 % longer boundary), a shadow sent
// again carries only its pose and velocity, the soft step's nine rounds only velocities (under
// Open MPI's 4 KB eager limit: 1 us a round, 3 us above it), and the rows go back in id order
// once the patches have scattered them (OrderRows): 2 ranks take 1.1-1.2 ms, 85-90 % of one
// rank's speed in the sets measured on this noisy VM; what is left is mostly the ranks waiting
// for each other at the step's 13 meetings (the one after the collide stage: 10-40 us a step).
// On a dense scene the gap was the Jacobi solve itself (many_pyramids, 2757 boxes: 85 % of the
// step, one rank 3x the World at 8 iterations, which do not hold the pyramids); the soft step
// per rank (kSoftStep: the World's solver on the local arrays, shadows' states from their owners
// between passes) makes one rank the World (same bits) plus the rank's bookkeeping. It is
// Gauss-Seidel inside a rank and Jacobi across the boundary; what holds a pyramid across ranks
// there is the exchange after the warm start (a shadow's warm start holds only this rank's rows)
// and recycling the manifolds as the World does.
#include "quadrant/distributed_world.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <type_traits>
#include <utility>

#include "collision/broad_phase.h"
#include "collision/contact_sort.h"
#include "dynamics/jacobi_solve.h"
#include "dynamics/soft_step.h"
#include "quadrant/bit_hash.h"
#include "quadrant/task_system.h"
#include "parallel/stage_runner.h"
#include "world/validation.h"
#include "world/world_internal.h"

namespace quadrant {
namespace {

// A body as it travels between ranks: everything a rank needs to collide, solve and integrate
// it. Mass data travels (it is not recomputed) so a shadow holds exactly its owner's bits.
struct Record {
  uint32_t id;
  BodyType type;
  Transform xf;
  Vec2 center;
  Vec2 localCenter;
  BodyVelocity vel;
  BodyInverseMass inv;
  Real mass, inertia, linearDamping, angularDamping, boundRadius;
  ShapeDef shape;
  Filter filter;
};
static_assert(std::is_trivially_copyable_v<Record>);

// A shadow message (round 2) is a run of entries in the owner's id order, each a header and then
// a Record (a body the receiver did not hold as this neighbour's shadow last step, or any body
// when the layouts start again) or only what a step changes: a body's mass, shape, filter and
// damping are the same every step (no setter reaches a distributed world's bodies), so a shadow
// sent again carries its pose and velocity (36 of 268 bytes in float builds). At 2 ranks x 16004
// circles about 100 shadows a rank, nearly all sent again each step: making their records read
// about 14 arrays at a random row each, and writing them about 20 (docs/notes/distributed.md).
struct ShadowHeader {
  uint32_t id;
  uint32_t full;  // 1: a Record follows; 0: a ShadowState
};
struct ShadowState {
  Transform xf;
  Vec2 center;
  BodyVelocity vel;
};
static_assert(std::is_trivially_copyable_v<ShadowHeader> && std::is_trivially_copyable_v<ShadowState>);

// A warm-start entry keyed by the pair of body ids (ContactCache keys by dense index, which in a
// World without destroyed bodies is the same order).
struct CacheEntry {
  uint64_t key;
  int32_t pointCount;
  uint32_t ids[2];
  Real normalImpulse[2];
  Real tangentImpulse[2];
};
static_assert(std::is_trivially_copyable_v<CacheEntry>);

// The velocity exchange of the solve: a boundary body's velocity, the pseudo velocity of its
// split impulses (JacobiSolve::Pseudo) and its contact count.
struct VelocityRecord {
  BodyVelocity vel;
  BodyVelocity pseudo;
  int32_t count;
};
static_assert(std::is_trivially_copyable_v<VelocityRecord>);

uint64_t PairKey(uint32_t a, uint32_t b) { return (uint64_t(a) << 32) | b; }

// Require whose message is made only when the check fails: for checks made per body or per step.
template <class Message>
  requires std::is_invocable_r_v<std::string, Message>
void Require(bool ok, Message&& message) {
  if (!ok) throw Error(message());
}

// splitmix64: the id checksum sums a mixed id so that a lost body and a duplicated one cannot
// cancel (a plain sum of ids can: lose 3, duplicate 1 and 2).
uint64_t MixId(uint64_t x) {
  x += 0x9e3779b97f4a7c15ull;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
  return x ^ (x >> 31);
}

template <class T>
void Put(std::vector<char>& buf, const T& value) {
  const size_t at = buf.size();
  buf.resize(at + sizeof(T));
  std::memcpy(buf.data() + at, &value, sizeof(T));
}

template <class T>
T Take(const std::vector<char>& buf, size_t& at) {
  if (at + sizeof(T) > buf.size()) throw std::logic_error("DistributedWorld: truncated message");
  T value;
  std::memcpy(&value, buf.data() + at, sizeof(T));
  at += sizeof(T);
  return value;
}

// The tiles of [x0, x1) x [y0, y1) in bisection order: the longer side cut (y on a tie), the
// lower part's tiles first, recursively. The cut is the row or column that splits the
// rectangle's cost (cost[tile]) most evenly; on equal costs the middle (the lower part the
// smaller on an odd count). On a power-of-two square grid of equal costs this is Morton (Z)
// order; on any other its runs stay compact, where Morton order's do not: 22 x 22 tiles at 2
// ranks, its first half is most of the 16 x 16 corner and the second an L around it (a boundary
// of 32 tiles where a cut has 22, and the L's grid twice its area), bisection gives two 22 x 11
// halves. Weighted by the bodies in each tile, a scene whose bodies are not spread evenly is cut
// straight where it balances (many_pyramids on 15 x 15 tiles: the middle cut left one of 2 ranks
// 9.8 % over the mean work).
void BisectionOrder(int x0, int x1, int y0, int y1, int tilesX, const std::vector<int64_t>& cost, std::vector<int>& order) {
  if (x1 - x0 <= 0 || y1 - y0 <= 0) return;
  if (x1 - x0 == 1 && y1 - y0 == 1) {
    order.push_back(x0 + y0 * tilesX);
    return;
  }
  const bool alongY = y1 - y0 >= x1 - x0;
  const int lo = alongY ? y0 : x0, hi = alongY ? y1 : x1, middle = lo + (hi - lo) / 2;
  std::vector<int64_t> line(size_t(hi - lo), 0);  // each row's (or column's) cost in the rectangle
  for (int y = y0; y < y1; ++y) {
    for (int x = x0; x < x1; ++x) line[size_t((alongY ? y : x) - lo)] += cost[size_t(x + y * tilesX)];
  }
  int64_t total = 0;
  for (int64_t c : line) total += c;
  int cut = middle;
  int64_t below = 0, best = INT64_MAX;
  for (int k = lo + 1; total > 0 && k < hi; ++k) {
    below += line[size_t(k - 1 - lo)];
    const int64_t off = std::abs(2 * below - total);
    if (off < best || (off == best && std::abs(k - middle) < std::abs(cut - middle))) {
      best = off;
      cut = k;
    }
  }
  if (alongY) {
    BisectionOrder(x0, x1, y0, cut, tilesX, cost, order);
    BisectionOrder(x0, x1, cut, y1, tilesX, cost, order);
  } else {
    BisectionOrder(x0, cut, y0, y1, tilesX, cost, order);
    BisectionOrder(cut, x1, y0, y1, tilesX, cost, order);
  }
}

uint64_t HashScene(std::span<const BodyDef> bodies) {
  BitHash h;
  auto mix = [&h](Real x) { h.Mix(x); };
  mix(Real(bodies.size() % (1u << 20)));
  mix(Real(bodies.size() >> 20));
  for (const BodyDef& b : bodies) {
    mix(Real(int(b.type)));
    mix(b.position.x), mix(b.position.y), mix(b.angle);
    mix(b.linearVelocity.x), mix(b.linearVelocity.y), mix(b.angularVelocity);
    mix(b.linearDamping), mix(b.angularDamping);
    const ShapeDef& s = b.shape;
    mix(Real(int(s.type)));
    mix(s.circle.center.x), mix(s.circle.center.y), mix(s.circle.radius);
    mix(Real(s.polygon.count));
    for (int k = 0; k < s.polygon.count && k < kMaxPolygonVertices; ++k) {
      mix(s.polygon.vertices[k].x), mix(s.polygon.vertices[k].y);
    }
    mix(s.density), mix(s.friction), mix(s.restitution);
    mix(b.gravityScale), mix(Real(b.fixedRotation ? 1 : 0)), mix(Real(b.isBullet ? 1 : 0));
    // 16 bits at a time: a float holds integers exactly only up to 2^24.
    for (uint32_t bits : {b.filter.categoryBits, b.filter.maskBits, uint32_t(b.filter.groupIndex)}) {
      mix(Real(bits & 0xFFFFu)), mix(Real(bits >> 16));
    }
  }
  return h.Value();
}

}  // namespace

struct DistributedWorld::Impl {
  WorldDef def;
  DistributedDef dist;
  MPI_Comm comm = MPI_COMM_NULL;
  int rank = 0, size = 1;
  Real tileW = 0, tileH = 0;
  double perTileX = 0, perTileY = 0;  // 1 / tile width and height: a body's tile by a multiplication
  std::vector<int> tileOwner;  // by tile index tx + ty * tilesX
  std::vector<int64_t> tileCost;  // this rank's work per tile in the last step (load balance)
  int64_t stepCount = 0;
  std::vector<int> ownedTile;  // owned index -> the tile its centre was in when the step began
  std::vector<double> haloReach;  // per block of the halo pass: the farthest reach
  std::vector<uint8_t> haloLost;  // per block: a body left its neighbourhood of tiles
  // Per block of the halo pass (blocks are contiguous and in order: concatenated, each list is in
  // owned order), only with neighbours: the owned bodies whose tile is another rank's (they
  // leave) and those in a tile of depth under 2 (deepTile: the only ones that may be a shadow
  // elsewhere). Migrate and SendShadows walk these lists, not the owned list: at 2 ranks x 16004
  // circles (Morton's L then) a quarter of the bodies were in such tiles, and with the lists the
  // migrate and shadows stages went from 0.035 and 0.079 to 0.028 and 0.063 ms a step.
  std::vector<std::vector<int>> haloLeaving, haloEdge;  // sized to the block (never shrunk: no refill)
  std::vector<size_t> haloLeavingCount, haloEdgeCount;  // per block: how many of each list are set
  std::vector<int> edgeOwned;  // owned indices of bodies in tiles of depth under 2, ascending
  std::vector<int> neighbours;  // ascending ranks
  std::vector<int> neighbourSlot;  // rank -> index in neighbours, -1 if not a neighbour
  // By tile: 2 if this rank owns every tile within two of it (5 x 5), 1 if every tile within one
  // (3 x 3), else 0. A body's box widened by the reach stays within 2 x reach of its centre (Step
  // checks 2 x reach <= a tile), so a body in a tile of depth 2 is a shadow nowhere, and one in a
  // tile of depth 1 neither while 2 x reach <= 0.99 tile (the 1 % a margin for rounding). At 2
  // ranks x 16004 circles the second rule halves the bodies SendShadows looks at.
  std::vector<uint8_t> deepTile;
  // ownBefore[(x) + (y) * (tilesX + 1)]: how many tiles of this rank lie in [0, x) x [0, y) (a 2D
  // prefix sum), so that whether a rectangle of tiles is all this rank's is four reads
  // (OwnAll): SendShadows asks it for every owned body outside the deep tiles.
  std::vector<int32_t> ownBefore;

  bool loaded = false;
  std::vector<Record> statics;  // every static body, on every rank, id order
  std::vector<Record> owned;    // this rank's moving bodies, id order
  std::vector<CacheEntry> cache;  // contacts of owned bodies, key order
  uint64_t expectedCount = 0, expectedChecksum = 0;

  std::unique_ptr<TaskSystem> tasks;
  std::unique_ptr<StageRunner> run;
  std::unique_ptr<BroadPhase> broadPhase;
  JacobiSolve solve;
  // kSoftStep: the World's soft step on the rank's owned bodies and shadows, the shadows' solver
  // states replaced by their owners' after every pass (ExchangeStates); the shadows' result is
  // dropped (their owners send them again next step).
  std::unique_ptr<SoftStepSolver> rankSolver;
  Profile rankProfile;
  double exchangeInSolveMs = 0;  // this step's ExchangeStates time (inside the soft step)
  // QUADRANT_CHECK_SHADOW_MOTION set: every round sends whole states, and where only the
  // velocities had to travel a shadow's dp and dq must already be its owner's bits (the tests).
  bool checkShadowMotion = std::getenv("QUADRANT_CHECK_SHADOW_MOTION") != nullptr;
  uint64_t motionMismatches = 0;  // shadows whose dp or dq differed (checkShadowMotion)
  std::vector<int32_t> contactCount;  // per local row: contacts this step (the tiles' work)
  DistributedStats stats;

  // Per-step scratch (kept between steps for its capacity).
  struct Source {
    uint32_t id;
    int kind;  // 0 static, 1 owned, 2 shadow
    int index;
    int neighbour;
  };
  std::vector<Source> sources;
  std::vector<size_t> runEnds;  // BuildLocal: where each id-ordered run of sources ends
  std::vector<Record> shadows;
  Bodies local;
  std::vector<uint8_t> localOwned;
  std::vector<uint8_t> pairMovable;  // per row: owned and dynamic (the broad phase's movable rows)
  std::vector<int> ownedLocal;                    // owned index -> local index
  std::vector<std::vector<int>> sentShadows;      // per neighbour: owned indices sent, in order
  std::vector<std::vector<int>> sentRows;         // per neighbour: their local rows (this step's layout)
  std::vector<std::vector<int>> receivedShadows;  // per neighbour: local indices, in order
  // Per neighbour: the ids sent last step (SendShadows: which shadows go as a ShadowState), and
  // this step's (sentIds).
  std::vector<std::vector<uint32_t>> prevSentIds, sentIds;
  // BuildLocal: this step's shadow entries per neighbour, parsed (id, whether a Record follows,
  // where its payload starts in in[k]).
  struct ShadowEntry {
    uint32_t id;
    bool full;
    size_t at;
  };
  std::vector<std::vector<ShadowEntry>> shadowIn;
  std::vector<int> shadowKeptRow;  // PatchLocal: per entry of a neighbour, its kept row (-1: new)
  std::vector<size_t> prevCursor;  // SendShadows: per neighbour, a cursor in prevSentIds
  std::vector<int> shadowTargets;  // SendShadows: the ranks one body goes to (kept for its capacity)
  std::vector<std::vector<char>> out, in;
  std::vector<CandidatePair> pairs, ownPairs;
  std::vector<MPI_Request> requests;              // PostVelocities: sends, then receives
  std::vector<MPI_Status> statuses;               // CompleteVelocities (kept for its capacity)
  std::vector<int32_t> interiorRows, boundaryRows;  // SplitRows: the solve's rows by whether they touch a shadow
  WorkerLists<Contact> workerContacts;
  ContactSorter sorter;
  std::vector<Contact> contacts;
  std::vector<Contact> lastContacts;  // kSoftStep: last step's, for recycling (FindContacts)
  std::vector<int32_t> recycleFirst;  // row -> its first contact as body a in lastContacts, or -1
  RecycleSource recycleSource;
  // Owned index -> this step's broad-phase box, only while the layout is not valid (the boxes come
  // from the records and the rebuild takes them); with a valid layout a body's box is its row's
  // (local.aabb, written by the halo pass) and an arrival's is made from its record: carrying the
  // boxes through Migrate's merge was 256 KB copied a step at 16004 circles.
  std::vector<AABB> ownedBoxes;
  std::vector<int> leavingIndex;             // Migrate: owned indices that leave (from the halo pass)
  std::vector<int> edgeNext, arrivalEdge;    // Migrate: edgeOwned renumbered for the new owned list
  std::vector<size_t> arrivalAt;             // Migrate: per arrival, the owned index it goes before
  std::vector<std::vector<uint32_t>> leavingIds;  // Migrate: per neighbour, the ids that go there
  // `local` holds last step's bodies in the order this step needs: no body left or arrived, no
  // tile changed owner, nothing loaded since. BuildLocal then only refreshes the shadows' rows
  // (if the same shadows came) and every box.
  bool layoutValid = false;
  // The rows of `local` are in id order (a rebuild's order; a patch gives it up): pairs and
  // contacts in row order are then in id order too, and FindContacts skips the translation.
  bool rowsInIdOrder = false;
  int localCustomFilters = 0;  // local bodies whose Filter is not the default (the pair filter runs)
  int localKinematic = 0;      // local kinematic bodies (FindContacts: every row movable then)
  // Where the owned bodies live. ownedStale false: `owned` holds every owned body's record, up
  // to date. ownedStale true (after every Step): `owned` is empty and the owned bodies are the
  // rows ownedLocal names in `local` (in any order), whose state is the newest; between
  // Migrate and BuildLocal a body that just arrived has ownedLocal -(1 + its index in `arrivals`).
  // Records are made from the rows where they travel (OwnedRecord) and all at once only where
  // they are read whole (SyncOwned): at 2 ranks a step used to refresh, compact and merge all
  // 16004 268-byte records whenever one body left or arrived (0.7 ms, as much as the collision).
  bool ownedStale = false;
  // Migrate changed the owned list (bodies left or arrived). With layoutValid still true, `local`
  // is last step's and ownedLocal maps the new list into it: BuildLocal patches it (PatchLocal)
  // instead of rebuilding it from records.
  bool ownedChanged = false;
  std::vector<Record> arrivals;              // Migrate: bodies that came this step, id order
  std::vector<Record> ownedNext;             // Migrate's merge scratch (kept for capacity)
  std::vector<int> ownedLocalNext, ownedTileNext;
  std::vector<AABB> ownedBoxesNext;
  std::vector<uint8_t> keepRow;              // PatchLocal: old rows that stay
  std::vector<int> freedRows;  // Migrate, PatchLocal: rows freed this step (the leavers', last step's shadows')
  std::vector<int> freeRows;                 // PatchLocal: rows to write, in the order they are taken
  std::vector<std::pair<int, int>> moves;    // PatchLocal: kept rows moved down (from, to), by from
  bool contactsRenumbered = false;           // PatchLocal renumbered last step's contacts (recycling)
  // QUADRANT_ORDER_ROWS set (the tests): OrderRows after every step, alternately into id order and
  // into its reverse, so that every step starts from rows laid out anew.
  bool orderRowsAlways = std::getenv("QUADRANT_ORDER_ROWS") != nullptr;
  std::vector<int> rowOrder, newRowOf;       // OrderRows: the rows in id order, and its inverse
  // PatchLocal: the new row of a kept row that moved (in `moves`).
  int MovedTo(int from) const {
    const auto it = std::lower_bound(moves.begin(), moves.end(), std::pair<int, int>{from, INT32_MIN});
    if (it == moves.end() || it->first != from) throw std::logic_error("DistributedWorld: a row past the end did not move");
    return it->second;
  }
  // Body id -> row for every row while rowOfIdValid (FindContacts' way back from id order): built
  // whole by the first patch after a rebuild, then kept by each patch for the rows it writes (a
  // rebuild each step was three passes over all rows, 0.03 ms of a 1.3 ms 2-rank circle step).
  std::vector<int32_t> rowOfId;
  bool rowOfIdValid = false;
  uint32_t idBound = 0;  // every row's id is below it (while rowOfIdValid)
  std::vector<uint64_t> countsAll;           // CheckCounts: every rank's count, checksum, work and motion mismatches

  size_t OwnedCount() const { return ownedStale ? ownedLocal.size() : owned.size(); }
  // This step's box of owned body o, between the halo pass and BuildLocal (see ownedBoxes).
  AABB OwnedBox(size_t o, Real dt) const {
    if (!layoutValid) return ownedBoxes[o];
    const int i = ownedLocal[o];
    return i >= 0 ? local.aabb[size_t(i)] : BoxOf(arrivals[size_t(-1 - i)], dt);
  }
  uint32_t OwnedId(size_t o) const {
    if (!ownedStale) return owned[o].id;
    const int i = ownedLocal[o];
    return i >= 0 ? local.slot[size_t(i)] : arrivals[size_t(-1 - i)].id;
  }
  // The owned body's record, up to date.
  Record OwnedRecord(size_t o) const {
    if (!ownedStale) return owned[o];
    const int i = ownedLocal[o];
    return i >= 0 ? ToRecord(local, i, local.slot[size_t(i)]) : arrivals[size_t(-1 - i)];
  }
  // Filled in place: while ownedStale, OwnedRecord reads the rows and arrivals, never `owned`
  // (a second list would add 268 bytes per owned body to the peak memory).
  void SyncOwned() {
    if (!ownedStale) return;
    owned.resize(OwnedCount());
    for (size_t o = 0; o < owned.size(); ++o) owned[o] = OwnedRecord(o);
    ownedStale = false;
  }

  // The tile column of x, clamped to the grid: floor by truncation, which is floor for the
  // positive values it is applied to (std::floor is a libm call without SSE4.1: it was half of
  // the shadows' pass, which asks for four tiles a body near the boundary).
  static int TileOf(double t, int tiles) { return t <= 0 ? 0 : t >= double(tiles - 1) ? tiles - 1 : int(t); }
  int TileX(Real x) const { return TileOf((double(x) - double(dist.bounds.lower.x)) * perTileX, dist.tilesX); }
  int TileY(Real y) const { return TileOf((double(y) - double(dist.bounds.lower.y)) * perTileY, dist.tilesY); }
  int OwnerOf(Vec2 c) const { return tileOwner[size_t(TileX(c.x) + TileY(c.y) * dist.tilesX)]; }
  // Whether every tile of [x0, x1] x [y0, y1] is this rank's (ownBefore).
  bool OwnAll(int x0, int x1, int y0, int y1) const {
    const size_t w1 = size_t(dist.tilesX) + 1;
    const auto at = [&](int x, int y) { return ownBefore[size_t(x) + size_t(y) * w1]; };
    return at(x1 + 1, y1 + 1) - at(x0, y1 + 1) - at(x1 + 1, y0) + at(x0, y0) == (x1 - x0 + 1) * (y1 - y0 + 1);
  }

  // One neighbour round: out[k] goes to neighbours[k] (every neighbour gets a message, empty or
  // not); in[k] is what neighbours[k] sent, read in rank order (a probe names its source).
  void Round(int tag) {
    const int n = static_cast<int>(neighbours.size());
    std::vector<MPI_Request> requests(size_t(n), MPI_REQUEST_NULL);
    for (int k = 0; k < n; ++k) {
      MPI_Isend(out[k].data(), static_cast<int>(out[k].size()), MPI_BYTE, neighbours[k], tag, comm, &requests[k]);
      stats.bytesSent += static_cast<int64_t>(out[k].size());
    }
    const auto waitFrom = std::chrono::steady_clock::now();
    for (int k = 0; k < n; ++k) {
      MPI_Status status;
      MPI_Probe(neighbours[k], tag, comm, &status);
      int count = 0;
      MPI_Get_count(&status, MPI_BYTE, &count);
      in[k].resize(size_t(count));
      MPI_Recv(in[k].data(), count, MPI_BYTE, neighbours[k], tag, comm, MPI_STATUS_IGNORE);
    }
    MPI_Waitall(n, requests.data(), MPI_STATUSES_IGNORE);
    stats.waitMs += std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - waitFrom).count();
    ++stats.rounds;
  }
  void ClearOut() {
    for (auto& b : out) b.clear();
  }

  static Record ToRecord(const Bodies& b, int i, uint32_t id) {
    Record r;
    std::memset(static_cast<void*>(&r), 0, sizeof r);  // padding included: messages carry no stray bytes
    r.id = id;
    r.type = b.type[i];
    r.xf = b.xf[i];
    r.center = b.center[i];
    r.localCenter = b.localCenter[i];
    r.vel = b.vel[i];
    r.inv = b.inv[i];
    r.mass = b.mass[i];
    r.inertia = b.inertia[i];
    r.linearDamping = b.linearDamping[i];
    r.angularDamping = b.angularDamping[i];
    r.boundRadius = b.boundRadius[i];
    r.shape = b.shape[i];
    r.filter = b.filter[i];
    return r;
  }

  static void SetRow(Bodies& b, int i, const Record& r) {
    b.type[i] = r.type;
    b.xf[i] = r.xf;
    b.center[i] = r.center;
    b.localCenter[i] = r.localCenter;
    b.vel[i] = r.vel;
    b.inv[i] = r.inv;
    b.mass[i] = r.mass;
    b.inertia[i] = r.inertia;
    b.linearDamping[i] = r.linearDamping;
    b.angularDamping[i] = r.angularDamping;
    b.shape[i] = r.shape;
    b.boxShape[i] = BoxShapeOf(r.shape);
    b.boundRadius[i] = r.boundRadius;
    b.dynamic[i] = r.type == BodyType::kDynamic ? 1 : 0;
    b.slot[i] = r.id;
    b.awake[i] = r.type == BodyType::kStatic ? 0 : 1;
    b.sleepTime[i] = 0;
    b.islandOf[i] = 0;
    b.filter[i] = r.filter;
  }

  // The broad-phase box of a record for a step of dt (the World's formula, world_internal.h).
  AABB BoxOf(const Record& r, Real dt) const { return SweptBox(r.shape, r.xf, r.vel, r.boundRadius, def, dt); }

  void DealTiles(const std::vector<int64_t>& cost);
  std::vector<int> Deal(const std::vector<int64_t>& cost) const;
  std::vector<int64_t> BodyCost(std::span<const Vec2> at) const;
  void FindNeighbours();
  void Rebalance(bool force);
  void Migrate(Real dt);
  void SendShadows(Real reach, Real dt);
  void BuildLocal(Real dt);
  void PatchLocal(Real dt);
  void OrderRows(bool reverse);
  // Owned bodies whose row does not follow the previous one's (how scattered the rows are).
  size_t RowsOutOfSequence() const {
    size_t out = 0;
    for (size_t o = 1; o < ownedLocal.size(); ++o) out += ownedLocal[o] != ownedLocal[o - 1] + 1 ? 1 : 0;
    return out;
  }
  // Writes a shadow entry of neighbour k into row i (a Record: the whole row; a ShadowState: pose
  // and velocity, the rest of the row is the body's already) and its box.
  void WriteShadow(size_t k, const ShadowEntry& e, int i, Real dt) {
    size_t at = e.at;
    if (e.full) {
      const Record r = Take<Record>(in[k], at);
      if (r.id != e.id) throw std::logic_error("DistributedWorld: a shadow record under another id");
      SetRow(local, i, r);
      local.aabb[size_t(i)] = BoxOf(r, dt);
    } else {
      const ShadowState st = Take<ShadowState>(in[k], at);
      local.xf[size_t(i)] = st.xf;
      local.center[size_t(i)] = st.center;
      local.vel[size_t(i)] = st.vel;
      local.aabb[size_t(i)] = BroadPhaseBox(local, i, def, dt);  // BoxOf's arithmetic (no bullets here)
    }
  }
  void FindContacts(Real dt);
  void PostVelocities(int tag);
  void PostShadowRound(int tag, size_t recordSize);
  void CompleteShadowRound(const char* what);
  void ExchangeStates(std::span<SolverBody> states, std::span<const uint8_t> inRows, bool rowsMoved);
  template <bool kWhole>
  void ExchangeStateRecords(std::span<SolverBody> states, std::span<const uint8_t> inRows, bool sameMotion);
  void CompleteVelocities(bool counts);
  void SplitRows();
  void StoreCache();
  void CheckCounts();
};

DistributedWorld::DistributedWorld(const WorldDef& def, const DistributedDef& dist, MPI_Comm comm)
    : impl_(std::make_unique<Impl>()) {
  Impl& w = *impl_;
  MPI_Comm_rank(comm, &w.rank);
  MPI_Comm_size(comm, &w.size);
  // Every check below reads only values every rank shares: all ranks throw alike.
  ValidateWorldDef(def);
  Require(def.solver == SolverType::kJacobi || def.solver == SolverType::kSoftStep,
          "DistributedWorld: WorldDef.solver must be kSoftStep (per rank) or kJacobi (the same bits on any rank count); "
          "pgs and thesis are not supported (see quadrant/distributed_world.h)");
  Require(!def.effects.sleep, "DistributedWorld: effects.sleep is not supported");
  Require(def.scheme == ParallelScheme::kDeterministic, "DistributedWorld: only ParallelScheme::kDeterministic");
  Require(IsFinite(dist.bounds.lower) && IsFinite(dist.bounds.upper) && dist.bounds.lower.x < dist.bounds.upper.x &&
              dist.bounds.lower.y < dist.bounds.upper.y,
          "DistributedDef.bounds must be finite and non-empty");
  Require(dist.tilesX >= 1 && dist.tilesX <= 1024 && dist.tilesY >= 1 && dist.tilesY <= 1024,
          "DistributedDef.tilesX and tilesY must be in [1, 1024]");
  Require(dist.rebalanceInterval >= 0, "DistributedDef.rebalanceInterval must be >= 0");
  Require(IsFinite(dist.rebalanceThreshold) && dist.rebalanceThreshold >= 1,
          "DistributedDef.rebalanceThreshold must be finite and >= 1");
  const int tiles = dist.tilesX * dist.tilesY;
  Require(w.size <= tiles, "DistributedWorld: " + std::to_string(w.size) + " ranks but only " + std::to_string(tiles) +
                               " tiles (" + std::to_string(dist.tilesX) + " x " + std::to_string(dist.tilesY) +
                               "): every rank needs at least one tile");
  w.def = def;
  w.dist = dist;
  MPI_Comm_dup(comm, &w.comm);
  w.tileW = (dist.bounds.upper.x - dist.bounds.lower.x) / Real(dist.tilesX);
  w.tileH = (dist.bounds.upper.y - dist.bounds.lower.y) / Real(dist.tilesY);
  w.perTileX = 1.0 / double(w.tileW);
  w.perTileY = 1.0 / double(w.tileH);

  // Tiles in bisection order, dealt in contiguous runs: at first equal numbers of tiles per rank
  // (Load and ReadCheckpoint deal them again by the bodies in each tile).
  w.tileCost.assign(static_cast<size_t>(tiles), 0);
  w.DealTiles(std::vector<int64_t>(static_cast<size_t>(tiles), 1));
  w.tasks = MakeThreadPool(def.threadCount);
  w.run = std::make_unique<StageRunner>(*w.tasks, def.minParallelItems);
  w.broadPhase = MakeBroadPhase(def.broadPhase, def.quadTreeMaxDepth);
  if (def.solver == SolverType::kSoftStep) {
    w.rankSolver = std::make_unique<SoftStepSolver>();
    w.rankSolver->SetStateExchange([&w](std::span<SolverBody> states, std::span<const uint8_t> inRows, bool rowsMoved) {
      if (!w.neighbours.empty()) w.ExchangeStates(states, inRows, rowsMoved);
    });
  }
}

// Deals the tiles, in bisection order, to the ranks in contiguous runs of about equal total cost
// (every rank at least one tile): rank r's run ends at the first tile whose middle passes
// (r + 1) / P of the total. Equal costs give equal numbers of tiles.
// The tiles in bisection order weighted by cost, dealt in contiguous runs of equal cost (a rank
// gets at least one tile): every tile's owner, nothing changed.
std::vector<int> DistributedWorld::Impl::Deal(const std::vector<int64_t>& cost) const {
  std::vector<int> order, owner;
  BisectionOrder(0, dist.tilesX, 0, dist.tilesY, dist.tilesX, cost, order);
  const int tiles = static_cast<int>(order.size());
  std::vector<int64_t> prefix(size_t(tiles) + 1, 0);
  for (int i = 0; i < tiles; ++i) prefix[size_t(i) + 1] = prefix[size_t(i)] + cost[size_t(order[size_t(i)])];
  const double total = double(prefix[size_t(tiles)]);
  owner.assign(size_t(tiles), 0);
  int start = 0;
  for (int r = 0; r < size; ++r) {
    int end = tiles;
    if (r + 1 < size) {
      const double target = total * double(r + 1) / double(size);
      end = start + 1;
      const int last = tiles - (size - 1 - r);  // leave a tile for every later rank
      while (end < last && double(prefix[size_t(end)]) + 0.5 * double(cost[size_t(order[size_t(end)])]) <= target) ++end;
    }
    for (int i = start; i < end; ++i) owner[size_t(order[size_t(i)])] = r;
    start = end;
  }
  return owner;
}

void DistributedWorld::Impl::DealTiles(const std::vector<int64_t>& cost) {
  tileOwner = Deal(cost);
  FindNeighbours();
}

// Bodies (not statics) per tile by where they are, for Load's and ReadCheckpoint's deal; a tile's
// cost is at least 1 where no tile holds a body (an empty scene is dealt by tiles).
std::vector<int64_t> DistributedWorld::Impl::BodyCost(std::span<const Vec2> at) const {
  std::vector<int64_t> cost(size_t(dist.tilesX) * size_t(dist.tilesY), 0);
  for (const Vec2 p : at) {
    if (IsFinite(p)) ++cost[size_t(TileX(p.x) + TileY(p.y) * dist.tilesX)];  // Load refuses the others
  }
  if (at.empty()) std::fill(cost.begin(), cost.end(), 1);
  return cost;
}

// The ranks owning a tile next to one of this rank's (8-neighbourhood), ascending.
void DistributedWorld::Impl::FindNeighbours() {
  neighbours.clear();
  neighbourSlot.assign(static_cast<size_t>(size), -1);
  const int tiles = dist.tilesX * dist.tilesY;
  for (int t = 0; t < tiles; ++t) {
    if (tileOwner[size_t(t)] != rank) continue;
    const int tx = t % dist.tilesX, ty = t / dist.tilesX;
    for (int dy = -1; dy <= 1; ++dy) {
      for (int dx = -1; dx <= 1; ++dx) {
        const int x = tx + dx, y = ty + dy;
        if (x < 0 || y < 0 || x >= dist.tilesX || y >= dist.tilesY) continue;
        const int owner = tileOwner[size_t(x + y * dist.tilesX)];
        if (owner != rank) neighbourSlot[size_t(owner)] = 0;
      }
    }
  }
  deepTile.assign(size_t(tiles), 0);
  const auto ownWithin = [&](int tx, int ty, int d) {
    for (int y = std::max(ty - d, 0); y <= std::min(ty + d, dist.tilesY - 1); ++y) {
      for (int x = std::max(tx - d, 0); x <= std::min(tx + d, dist.tilesX - 1); ++x) {
        if (tileOwner[size_t(x + y * dist.tilesX)] != rank) return false;
      }
    }
    return true;
  };
  for (int t = 0; t < tiles; ++t) {
    const int tx = t % dist.tilesX, ty = t / dist.tilesX;
    deepTile[size_t(t)] = ownWithin(tx, ty, 2) ? 2 : ownWithin(tx, ty, 1) ? 1 : 0;
  }
  const size_t w1 = size_t(dist.tilesX) + 1;
  ownBefore.assign(w1 * (size_t(dist.tilesY) + 1), 0);
  for (int y = 0; y < dist.tilesY; ++y) {
    for (int x = 0; x < dist.tilesX; ++x) {
      const int own = tileOwner[size_t(x + y * dist.tilesX)] == rank ? 1 : 0;
      ownBefore[size_t(x + 1) + size_t(y + 1) * w1] =
          own + ownBefore[size_t(x) + size_t(y + 1) * w1] + ownBefore[size_t(x + 1) + size_t(y) * w1] - ownBefore[size_t(x) + size_t(y) * w1];
    }
  }
  for (int r = 0; r < size; ++r) {
    if (neighbourSlot[size_t(r)] == 0) {
      neighbourSlot[size_t(r)] = static_cast<int>(neighbours.size());
      neighbours.push_back(r);
    }
  }
  const size_t nb = neighbours.size();
  out.assign(nb, {});
  in.assign(nb, {});
  sentShadows.assign(nb, {});
  receivedShadows.assign(nb, {});
  prevSentIds.assign(nb, {});
  sentIds.assign(nb, {});
  shadowIn.assign(nb, {});
  stats.neighbours = static_cast<int>(nb);
  layoutValid = false;  // the neighbours' message slots start again
}

// Load balance: the tiles' costs of the last step (bodies owned plus their contacts: counts, not
// times, so the new partition is the same on every run) summed over the ranks; if the most loaded
// rank carries more than threshold times the mean (or `force`), the tiles are dealt again by cost
// and every body whose tile changed owner moves there with its warm-start entries (one
// all-to-all: a new owner need not be a neighbour). The arithmetic of a step does not depend on
// the partition, so the states are the same bits with or without it.
void DistributedWorld::Impl::Rebalance(bool force) {
  std::vector<int64_t> cost(tileCost.size(), 0);
  MPI_Allreduce(tileCost.data(), cost.data(), static_cast<int>(cost.size()), MPI_INT64_T, MPI_SUM, comm);
  std::vector<double> perRank(size_t(size), 0.0);
  double total = 0;
  for (size_t t = 0; t < cost.size(); ++t) {
    perRank[size_t(tileOwner[t])] += double(cost[t]);
    total += double(cost[t]);
  }
  const double imbalance = total > 0 ? *std::max_element(perRank.begin(), perRank.end()) / (total / size) : 1.0;
  if (!force && !(imbalance > double(dist.rebalanceThreshold))) return;
  if (total <= 0) return;
  SyncOwned();
  DealTiles(cost);
  ++stats.rebalances;

  std::vector<std::vector<char>> to(static_cast<size_t>(size));
  std::vector<std::vector<uint32_t>> leaving(static_cast<size_t>(size));
  std::vector<Record> staying;
  for (const Record& r : owned) {
    const int owner = OwnerOf(r.center);
    if (owner == rank) {
      staying.push_back(r);
    } else {
      leaving[size_t(owner)].push_back(r.id);
      Put(to[size_t(owner)], r);
    }
  }
  std::vector<char> send;
  std::vector<int> sendCounts(size_t(size), 0), sendDispls(size_t(size), 0);
  for (int r = 0; r < size; ++r) {
    sendDispls[size_t(r)] = static_cast<int>(send.size());
    Put(send, uint32_t(leaving[size_t(r)].size()));
    send.insert(send.end(), to[size_t(r)].begin(), to[size_t(r)].end());
    std::vector<char> entries;
    uint32_t n = 0;
    const auto& ids = leaving[size_t(r)];
    for (const CacheEntry& e : cache) {
      if (std::binary_search(ids.begin(), ids.end(), uint32_t(e.key >> 32)) ||
          std::binary_search(ids.begin(), ids.end(), uint32_t(e.key))) {
        Put(entries, e);
        ++n;
      }
    }
    Put(send, n);
    send.insert(send.end(), entries.begin(), entries.end());
    sendCounts[size_t(r)] = static_cast<int>(send.size()) - sendDispls[size_t(r)];
  }
  std::vector<int> recvCounts(size_t(size), 0), recvDispls(size_t(size), 0);
  MPI_Alltoall(sendCounts.data(), 1, MPI_INT, recvCounts.data(), 1, MPI_INT, comm);
  int totalRecv = 0;
  for (int r = 0; r < size; ++r) {
    recvDispls[size_t(r)] = totalRecv;
    totalRecv += recvCounts[size_t(r)];
  }
  std::vector<char> recv(static_cast<size_t>(totalRecv));
  MPI_Alltoallv(send.data(), sendCounts.data(), sendDispls.data(), MPI_BYTE, recv.data(), recvCounts.data(),
                recvDispls.data(), MPI_BYTE, comm);
  owned.swap(staying);
  for (int r = 0; r < size; ++r) {
    const std::vector<char> part(recv.begin() + recvDispls[size_t(r)],
                                 recv.begin() + recvDispls[size_t(r)] + recvCounts[size_t(r)]);
    size_t at = 0;
    const uint32_t bodies = Take<uint32_t>(part, at);
    for (uint32_t j = 0; j < bodies; ++j) owned.push_back(Take<Record>(part, at));
    const uint32_t entries = Take<uint32_t>(part, at);
    for (uint32_t j = 0; j < entries; ++j) cache.push_back(Take<CacheEntry>(part, at));
  }
  std::sort(owned.begin(), owned.end(), [](const Record& a, const Record& b) { return a.id < b.id; });
  std::stable_sort(cache.begin(), cache.end(), [](const CacheEntry& a, const CacheEntry& b) { return a.key < b.key; });
  cache.erase(std::unique(cache.begin(), cache.end(), [](const CacheEntry& a, const CacheEntry& b) { return a.key == b.key; }),
              cache.end());
}

DistributedWorld::~DistributedWorld() {
  if (impl_ && impl_->comm != MPI_COMM_NULL) MPI_Comm_free(&impl_->comm);
}

void DistributedWorld::Load(std::span<const BodyDef> bodies) {
  Impl& w = *impl_;
  // The same scene on every rank, checked by its hash: min and max over the ranks agree.
  const uint64_t hash = HashScene(bodies);
  uint64_t lo = 0, hi = 0;
  MPI_Allreduce(&hash, &lo, 1, MPI_UINT64_T, MPI_MIN, w.comm);
  MPI_Allreduce(&hash, &hi, 1, MPI_UINT64_T, MPI_MAX, w.comm);
  Require(lo == hi, "DistributedWorld::Load: the scene differs between ranks (scene hashes range from " +
                        std::to_string(lo) + " to " + std::to_string(hi) + ")");
  Require(bodies.size() < (uint64_t(1) << 31), "DistributedWorld::Load: more than 2^31 bodies");
  // Rows made by the World's own code (validation and mass data): the same bits as a World's.
  // Identical scenes make every rank refuse the same body with the same message.
  // Each body is made in a one-row scratch and kept only if it is static or this rank's, so a
  // rank holds its share of a large scene, not all of it (the caller's BodyDefs aside).
  // The tiles dealt by the bodies in each (by position: the same on every rank), applied once
  // every body is accepted.
  std::vector<Vec2> moving;
  for (const BodyDef& b : bodies) {
    if (b.type != BodyType::kStatic) moving.push_back(b.position);
  }
  std::vector<int> tileOwner = w.Deal(w.BodyCost(moving));
  std::vector<Vec2>().swap(moving);
  std::vector<Record> statics, owned;
  uint64_t count = 0, checksum = 0;
  Bodies row;
  for (size_t i = 0; i < bodies.size(); ++i) {
    // The pre-solve pass and the bullet sweep are the World's (world.cpp), not this world's.
    Require(bodies[i].gravityScale == 1 && !bodies[i].isBullet, [&] {
      return "DistributedWorld::Load: body " + std::to_string(i) + ": gravityScale other than 1 and isBullet are not supported";
    });
    row.ForEachArray([](auto& v) { v.clear(); });
    // Its ranks find pairs on their own and collide every one (FindContacts).
    Require(!bodies[i].shape.isSensor,
            [&] { return "DistributedWorld::Load: sensor shapes are not supported (body " + std::to_string(i) + ")"; });
    // A rank's record carries a circle or a polygon (ToRecord).
    Require(bodies[i].shape.type != ShapeType::kCapsule,
            [&] { return "DistributedWorld::Load: capsule shapes are not supported (body " + std::to_string(i) + ")"; });
    Require(!IsSegmentType(bodies[i].shape.type),
            [&] { return "DistributedWorld::Load: segment shapes are not supported (body " + std::to_string(i) + ")"; });
    Require(bodies[i].extraShapes.empty(), [&] {
      return "DistributedWorld::Load: compound bodies (BodyDef.extraShapes) are not supported (body " + std::to_string(i) + ")";
    });
    AppendBody(row, bodies[i], w.def, static_cast<uint32_t>(i));
    const Record r = Impl::ToRecord(row, 0, static_cast<uint32_t>(i));
    if (r.type == BodyType::kStatic) {
      statics.push_back(r);
      continue;
    }
    ++count;
    checksum += MixId(r.id);
    if (tileOwner[size_t(w.TileX(r.center.x) + w.TileY(r.center.y) * w.dist.tilesX)] == w.rank) owned.push_back(r);
  }
  w.tileOwner.swap(tileOwner);
  w.FindNeighbours();
  w.statics.swap(statics);
  w.owned.swap(owned);
  w.cache.clear();
  w.layoutValid = false;
  w.ownedStale = false;
  w.expectedCount = count;
  w.expectedChecksum = checksum;
  w.loaded = true;
  std::fill(w.tileCost.begin(), w.tileCost.end(), 0);
  w.CheckCounts();
}

void DistributedWorld::Step(Real dt) {
  Require(IsFinite(dt) && dt > 0, "Step: dt must be finite and > 0");
  Require(dt <= kMaxTimeStep, "Step: dt must be <= 1 s");
  Impl& w = *impl_;
  Require(w.loaded, "DistributedWorld::Step: Load a scene first");
  const DistributedStats previous = w.stats;
  w.stats = DistributedStats{};
  w.stats.neighbours = previous.neighbours;
  if (w.dist.rebalanceInterval > 0 && w.stepCount > 0 && w.stepCount % w.dist.rebalanceInterval == 0) {
    w.Rebalance(false);
  }
  ++w.stepCount;
  using StageTime = std::chrono::steady_clock;
  auto mark = StageTime::now();
  auto lap = [&mark](double& into) {
    const auto now = StageTime::now();
    into += std::chrono::duration<double, std::milli>(now - mark).count();
    mark = now;
  };

  // The halo: the farthest any moving body's box reaches from its centre this step, over all
  // ranks (a max is exact in any order), and whether any body left its neighbourhood of tiles.
  // Each owned body's box and tile are kept for the rest of the step; read from the local arrays
  // while they map the owned list (layoutValid), else from the records. In parallel over the
  // rank's threads, as the World boxes its bodies: on one thread this pass is 0.22 ms of a 1.1 ms
  // step (16004 circles); one rank x 2 threads on 64004 circles went from 5.2 to 3.5 ms a step
  // with it (medians of five interleaved pairs, docs/notes/distributed.md).
  w.run->BeginStep();  // as World::Step: wake the pool's workers, or run alone on a busy machine
  const size_t ownedCount = w.OwnedCount();
  if (!w.layoutValid) w.ownedBoxes.resize(ownedCount);
  w.ownedTile.resize(ownedCount);
  const int blocks = w.run->Workers();
  w.haloReach.assign(size_t(blocks), 0);
  w.haloLost.assign(size_t(blocks), 0);
  const bool lists = !w.neighbours.empty();
  w.haloLeaving.resize(size_t(blocks));
  w.haloEdge.resize(size_t(blocks));
  w.haloLeavingCount.assign(size_t(blocks), 0);  // a block that gets no items adds nothing
  w.haloEdgeCount.assign(size_t(blocks), 0);
  w.run->For(Stage::kBroadPhase, static_cast<int>(ownedCount), w.run->MinItems(), [&w, dt, lists](int begin, int end, int block) {
    double most = 0;
    uint8_t lost = 0;
    // Written without a branch (a body's tile is deep or not at random in owned order): each
    // index goes to the next place of both lists, which advance only where it belongs.
    std::vector<int>& leaving = w.haloLeaving[size_t(block)];
    std::vector<int>& edge = w.haloEdge[size_t(block)];
    size_t leavingCount = 0, edgeCount = 0;
    if (lists) {
      leaving.resize(std::max(leaving.size(), size_t(end - begin)));
      edge.resize(std::max(edge.size(), size_t(end - begin)));
    }
    for (size_t o = size_t(begin); o < size_t(end); ++o) {
      Vec2 c;
      AABB box;
      if (w.layoutValid) {
        // The local rows hold the newest state whenever the layout is valid (SyncOwned only copies
        // them to the records); the box goes to the row too, which BuildLocal keeps if it can.
        const int i = w.ownedLocal[o];
        c = w.local.center[size_t(i)];
        box = w.local.aabb[size_t(i)] = BroadPhaseBox(w.local, i, w.def, dt);
      } else {
        c = w.owned[o].center;
        box = w.BoxOf(w.owned[o], dt);
      }
      if (!w.layoutValid) w.ownedBoxes[o] = box;
      const double reach = std::max({double(c.x - box.lower.x), double(box.upper.x - c.x), double(c.y - box.lower.y),
                                     double(box.upper.y - c.y)});
      most = std::max(most, reach);
      const int t = w.TileX(c.x) + w.TileY(c.y) * w.dist.tilesX;
      w.ownedTile[o] = t;
      const int owner = w.tileOwner[size_t(t)];
      if (owner != w.rank && w.neighbourSlot[size_t(owner)] < 0) lost = 1;
      if (lists) {
        leaving[leavingCount] = edge[edgeCount] = static_cast<int>(o);
        leavingCount += owner != w.rank ? 1 : 0;
        edgeCount += owner == w.rank && w.deepTile[size_t(t)] < 2 ? 1 : 0;
      }
    }
    w.haloLeavingCount[size_t(block)] = leavingCount;
    w.haloEdgeCount[size_t(block)] = edgeCount;
    w.haloReach[size_t(block)] = std::max(w.haloReach[size_t(block)], most);
    w.haloLost[size_t(block)] |= lost;
  });
  w.leavingIndex.clear();
  w.edgeOwned.clear();
  for (int b = 0; b < blocks; ++b) {
    const auto& leaving = w.haloLeaving[size_t(b)];
    const auto& edge = w.haloEdge[size_t(b)];
    w.leavingIndex.insert(w.leavingIndex.end(), leaving.begin(), leaving.begin() + std::ptrdiff_t(w.haloLeavingCount[size_t(b)]));
    w.edgeOwned.insert(w.edgeOwned.end(), edge.begin(), edge.begin() + std::ptrdiff_t(w.haloEdgeCount[size_t(b)]));
  }
  double local[2] = {0, 0};
  for (int b = 0; b < blocks; ++b) {
    local[0] = std::max(local[0], w.haloReach[size_t(b)]);
    if (w.haloLost[size_t(b)]) local[1] = 1;
  }
  double global[2] = {0, 0};
  {
    const auto waitFrom = StageTime::now();
    MPI_Allreduce(local, global, 2, MPI_DOUBLE, MPI_MAX, w.comm);
    w.stats.waitMs += std::chrono::duration<double, std::milli>(StageTime::now() - waitFrom).count();
  }
  const double tile = std::min(double(w.tileW), double(w.tileH));
  Require(2 * global[0] <= tile, [&] {
    return "DistributedWorld::Step: a body's broad-phase box reaches " + std::to_string(global[0]) +
           " m from its centre, more than half a tile (" + std::to_string(tile) +
           " m): the body is too large (or too fast) for the tiles; use fewer tiles";
  });
  Require(global[1] == 0, "DistributedWorld::Step: a body moved past the tiles next to its own in one step");
  lap(w.stats.haloMs);

  w.Migrate(dt);  // keeps ownedTile (and ownedBoxes, if in use) in step with the owned list
  lap(w.stats.migrateMs);
  w.SendShadows(Real(global[0]), dt);
  lap(w.stats.shadowsMs);
  w.BuildLocal(dt);
  // The rows of the bodies that are shadows elsewhere, for the solvers' rounds (9 a step with
  // the soft step: each looked them up through ownedLocal).
  w.sentRows.resize(w.neighbours.size());
  for (size_t k = 0; k < w.neighbours.size(); ++k) {
    w.sentRows[k].resize(w.sentShadows[k].size());
    for (size_t j = 0; j < w.sentShadows[k].size(); ++j) w.sentRows[k][j] = w.ownedLocal[size_t(w.sentShadows[k][j])];
  }
  w.FindContacts(dt);
  lap(w.stats.collideMs);

  if (w.rankSolver) {
    // WorldDef's solver on the rank's bodies and shadows, as a World steps its bodies: the
    // ranks meet once a step (the shadows), not once an iteration.
    StepContext ctx;
    ctx.dt = dt;
    ctx.def = &w.def;
    ctx.bodies = &w.local;
    ctx.contacts = w.contacts;
    ctx.profile = &w.rankProfile;
    ctx.run = w.run.get();
    w.exchangeInSolveMs = 0;
    w.rankSolver->Step(ctx);
    lap(w.stats.solveMs);
    w.stats.solveMs -= w.exchangeInSolveMs;
    w.stats.exchangeMs += w.exchangeInSolveMs;
  } else {
    const int k = w.def.velocityIterations;
    IntegrateVelocities(w.local, w.def, dt, *w.run);
    w.solve.Begin(w.local, w.def, dt, w.contacts);
    lap(w.stats.solveMs);
    if (w.neighbours.empty()) {
      // No neighbour (one rank): the rounds carry nothing; the solve in one piece.
      w.solve.Prepare(w.def);
      for (int it = 0; it < k; ++it) w.solve.Iterate(w.local, w.def);
      w.stats.rounds += k;
      lap(w.stats.solveMs);
    } else {
      // Each round's messages travel while the interior rows are solved (the first round's while
      // they are prepared too); the boundary rows wait for them. Rounds: the counts after warm
      // starting, then the velocities after every iteration but the last.
      w.SplitRows();
      w.PostVelocities(3);
      w.solve.PrepareRows(w.def, w.interiorRows);
      for (int it = 0; it < k; ++it) {
        w.solve.SolveRows(w.local, w.def, w.interiorRows);
        lap(w.stats.solveMs);
        w.CompleteVelocities(it == 0);
        lap(w.stats.exchangeMs);
        if (it == 0) w.solve.PrepareRows(w.def, w.boundaryRows);
        w.solve.SolveRows(w.local, w.def, w.boundaryRows);
        w.solve.ApplyRows(w.local);
        lap(w.stats.solveMs);
        if (it + 1 < k) {
          w.PostVelocities(4);
          lap(w.stats.exchangeMs);
        }
      }
    }
    w.solve.Finish(w.local, w.def, dt, w.contacts, *w.run);
    lap(w.stats.solveMs);
  }
  w.StoreCache();
  w.ownedStale = true;  // the owned bodies' new state is in `local`
  w.owned.clear();
  w.stats.ownedBodies = static_cast<int>(w.OwnedCount());
  w.stats.contacts = static_cast<int>(w.contacts.size());
  // Work per tile of this step, for load balancing: each owned body and each of its contacts,
  // booked to the tile its centre was in when the step began.
  std::fill(w.tileCost.begin(), w.tileCost.end(), 0);
  const std::vector<int32_t>& counts = w.rankSolver ? w.contactCount : w.solve.Counts();
  if (w.rankSolver) {
    w.contactCount.assign(size_t(w.local.Count()), 0);
    for (const Contact& c : w.contacts) {
      ++w.contactCount[size_t(c.a)];
      ++w.contactCount[size_t(c.b)];
    }
  }
  for (size_t o = 0; o < w.ownedLocal.size(); ++o) {
    w.tileCost[size_t(w.ownedTile[o])] += 1 + counts[size_t(w.ownedLocal[o])];
  }
  w.CheckCounts();
  if (w.orderRowsAlways) {
    w.OrderRows(w.stepCount % 2 == 1);
  } else if (!w.rowsInIdOrder && w.stepCount % 64 == 0 && w.RowsOutOfSequence() * 16 > w.ownedLocal.size()) {
    w.OrderRows(false);
  }
  lap(w.stats.restMs);
}

// Round 1: bodies whose centre is now in another rank's tile go there, with the warm-start
// entries of their contacts (the new owner computes those contacts next). Most steps move no body
// on most ranks: then the owned list is left as it is and the local arrays of the last step stay
// valid (BuildLocal). Otherwise the staying bodies and the arrivals are merged by id (the order a
// full sort would give) in one pass, with each body's box, tile and, while `local` maps the list,
// its row there; records are merged only where they hold the state (ownedStale false).
void DistributedWorld::Impl::Migrate(Real dt) {
  ClearOut();
  freedRows.clear();
  const size_t count = OwnedCount();
  // leavingIndex and edgeOwned: from the halo pass (no neighbour: nobody leaves).
  // Their rows, for a patch of the local arrays (PatchLocal), while the arrays map the list.
  if (layoutValid) {
    for (int o : leavingIndex) freedRows.push_back(ownedLocal[size_t(o)]);
  }
  leavingIds.resize(neighbours.size());
  for (auto& ids : leavingIds) ids.clear();
  for (int o : leavingIndex) {
    const Record r = OwnedRecord(size_t(o));
    const int k = neighbourSlot[size_t(OwnerOf(r.center))];  // checked collectively in Step
    leavingIds[size_t(k)].push_back(r.id);
    Put(out[size_t(k)], r);
  }
  for (size_t k = 0; k < neighbours.size(); ++k) {
    // Entries touching a leaving body, after a separator count of bodies (records first).
    const auto& ids = leavingIds[k];
    std::vector<char> message;
    Put(message, uint32_t(ids.size()));
    message.insert(message.end(), out[k].begin(), out[k].end());
    const size_t countAt = message.size();
    Put(message, uint32_t(0));
    uint32_t n = 0;
    if (!ids.empty()) {
      for (const CacheEntry& e : cache) {
        const uint32_t a = uint32_t(e.key >> 32), b = uint32_t(e.key);
        if (std::binary_search(ids.begin(), ids.end(), a) || std::binary_search(ids.begin(), ids.end(), b)) {
          Put(message, e);
          ++n;
        }
      }
    }
    std::memcpy(message.data() + countAt, &n, sizeof n);
    out[k].swap(message);
  }
  Round(1);
  arrivals.clear();
  const size_t cacheBefore = cache.size();
  for (size_t k = 0; k < neighbours.size(); ++k) {
    size_t at = 0;
    const uint32_t bodies = Take<uint32_t>(in[k], at);
    for (uint32_t j = 0; j < bodies; ++j) arrivals.push_back(Take<Record>(in[k], at));
    stats.migratedIn += static_cast<int>(bodies);
    const uint32_t entries = Take<uint32_t>(in[k], at);
    for (uint32_t j = 0; j < entries; ++j) cache.push_back(Take<CacheEntry>(in[k], at));
  }
  if (!leavingIndex.empty() || !arrivals.empty()) {
    const auto byId = [](const Record& a, const Record& b) { return a.id < b.id; };
    std::sort(arrivals.begin(), arrivals.end(), byId);
    // ownedLocal maps `local` only while the layout is valid; else BuildLocal rebuilds anyway.
    const bool carry = layoutValid;
    const bool records = !ownedStale;
    // The next lists are resized, not cleared: every element is written below, and a cleared
    // vector's resize fills all of them first (0.4 MB a step at 16004 circles).
    // The staying bodies are copied in runs between the events (a leaver; an arrival's place by
    // id, found by binary search): a merge that visited every body cost 85 instructions a body
    // (2 ranks, 16004 circles each: 1.35M of the step's 15.3M), nearly every step.
    arrivalAt.resize(arrivals.size());
    for (size_t j = 0; j < arrivals.size(); ++j) {
      size_t lo = 0, hi = count;
      while (lo < hi) {
        const size_t mid = (lo + hi) / 2;
        if (OwnedId(mid) < arrivals[j].id) {
          lo = mid + 1;
        } else {
          hi = mid;
        }
      }
      if (lo < count && OwnedId(lo) == arrivals[j].id) throw std::logic_error("DistributedWorld: a body arrived twice");
      arrivalAt[j] = lo;
    }
    const size_t newCount = count - leavingIndex.size() + arrivals.size();
    if (records) ownedNext.resize(newCount);
    ownedLocalNext.resize(newCount);
    if (!carry) ownedBoxesNext.resize(newCount);
    ownedTileNext.resize(newCount);
    size_t w = 0;
    const auto copyRun = [&](size_t from, size_t to) {
      if (to <= from) return;
      if (records) std::copy(owned.begin() + std::ptrdiff_t(from), owned.begin() + std::ptrdiff_t(to), ownedNext.begin() + std::ptrdiff_t(w));
      if (carry) {
        std::copy(ownedLocal.begin() + std::ptrdiff_t(from), ownedLocal.begin() + std::ptrdiff_t(to), ownedLocalNext.begin() + std::ptrdiff_t(w));
      } else {
        std::fill(ownedLocalNext.begin() + std::ptrdiff_t(w), ownedLocalNext.begin() + std::ptrdiff_t(w + to - from), -1);
      }
      if (!carry) {
        std::copy(ownedBoxes.begin() + std::ptrdiff_t(from), ownedBoxes.begin() + std::ptrdiff_t(to), ownedBoxesNext.begin() + std::ptrdiff_t(w));
      }
      std::copy(ownedTile.begin() + std::ptrdiff_t(from), ownedTile.begin() + std::ptrdiff_t(to), ownedTileNext.begin() + std::ptrdiff_t(w));
      w += to - from;
    };
    arrivalEdge.clear();
    size_t next = 0, a = 0, cur = 0;
    for (;;) {
      const size_t leave = next < leavingIndex.size() ? size_t(leavingIndex[next]) : count;
      const size_t arrive = a < arrivals.size() ? arrivalAt[a] : count;
      if (a < arrivals.size() && arrive <= leave) {
        copyRun(cur, arrive);
        cur = std::max(cur, arrive);
        const Record& r = arrivals[a];
        if (records) ownedNext[w] = r;
        ownedLocalNext[w] = -1 - static_cast<int>(a);
        if (!carry) ownedBoxesNext[w] = BoxOf(r, dt);
        ownedTileNext[w] = TileX(r.center.x) + TileY(r.center.y) * dist.tilesX;
        if (deepTile[size_t(ownedTileNext[w])] < 2) arrivalEdge.push_back(static_cast<int>(w));
        ++w;
        ++a;
      } else if (leave < count) {
        copyRun(cur, leave);
        cur = leave + 1;
        ++next;
      } else {
        copyRun(cur, count);
        break;
      }
    }
    if (w != newCount) throw std::logic_error("DistributedWorld: the owned list's merge miscounted");
    // A staying body o is now at o - (leavers before it) + (arrivals placed before it, at or
    // below o): both lists ascend, so the renumbered edge list does too; the arrivals in edge
    // tiles are merged in.
    edgeNext.clear();
    for (size_t e = 0, l = 0, b = 0; e < edgeOwned.size(); ++e) {
      const size_t o = size_t(edgeOwned[e]);
      while (l < leavingIndex.size() && size_t(leavingIndex[l]) < o) ++l;
      while (b < arrivalAt.size() && arrivalAt[b] <= o) ++b;
      edgeNext.push_back(static_cast<int>(o - l + b));
    }
    edgeOwned.resize(edgeNext.size() + arrivalEdge.size());
    std::merge(edgeNext.begin(), edgeNext.end(), arrivalEdge.begin(), arrivalEdge.end(), edgeOwned.begin());
    if (records) owned.swap(ownedNext);
    ownedLocal.swap(ownedLocalNext);
    if (!carry) ownedBoxes.swap(ownedBoxesNext);
    ownedTile.swap(ownedTileNext);
    ownedChanged = true;
  }
  if (cache.size() > cacheBefore) {
    // The same contact may arrive from two ranks (both bodies moved); the entries are equal (both
    // ranks computed it with the same arithmetic), so one is kept: the first, as a stable sort of
    // the whole list keeps it (the list is in key order, each key once, before the arrivals).
    const auto byKey = [](const CacheEntry& a, const CacheEntry& b) { return a.key < b.key; };
    std::stable_sort(cache.begin() + std::ptrdiff_t(cacheBefore), cache.end(), byKey);
    std::inplace_merge(cache.begin(), cache.begin() + std::ptrdiff_t(cacheBefore), cache.end(), byKey);
    cache.erase(std::unique(cache.begin(), cache.end(), [](const CacheEntry& a, const CacheEntry& b) { return a.key == b.key; }),
                cache.end());
  }
}

// Round 2: every owned body goes as a shadow to each other rank owning a tile that its box,
// widened by the global reach, overlaps. An owned body of that rank has its centre in such a tile
// and its box within `reach` of it, so every pair with one of its bodies is found there.
void DistributedWorld::Impl::SendShadows(Real reach, Real dt) {
  ClearOut();
  for (auto& s : sentShadows) s.clear();
  std::vector<int>& targets = shadowTargets;
  prevCursor.assign(neighbours.size(), 0);
  for (auto& ids : sentIds) ids.clear();
  // One rank, or no neighbour: nobody to send to (edgeOwned is empty). Otherwise the owned
  // bodies in tiles of depth under 2 (from the halo pass, renumbered by Migrate), in owned order.
  const uint8_t deepEnough = 2 * double(reach) <= 0.99 * std::min(double(tileW), double(tileH)) ? 1 : 2;
  for (const int edge : edgeOwned) {
    const size_t o = size_t(edge);
    if (deepTile[size_t(ownedTile[o])] >= deepEnough) continue;
    const AABB box = OwnedBox(o, dt);
    const int x0 = TileX(box.lower.x - reach), x1 = TileX(box.upper.x + reach);
    const int y0 = TileY(box.lower.y - reach), y1 = TileY(box.upper.y + reach);
    if (OwnAll(x0, x1, y0, y1)) continue;  // most bodies near the boundary: no owner to gather
    targets.clear();
    for (int y = y0; y <= y1; ++y) {
      for (int x = x0; x <= x1; ++x) {
        const int owner = tileOwner[size_t(x + y * dist.tilesX)];
        if (owner != rank) targets.push_back(owner);
      }
    }
    std::sort(targets.begin(), targets.end());
    targets.erase(std::unique(targets.begin(), targets.end()), targets.end());
    if (targets.empty()) continue;
    const uint32_t id = OwnedId(o);
    bool haveRecord = false;
    Record r;
    for (int t : targets) {
      const int k = neighbourSlot[size_t(t)];
      if (k < 0) throw std::logic_error("DistributedWorld: a shadow for a rank that is not a neighbour");
      // Sent to k last step (both lists ascend: a cursor per neighbour), and k kept its layout.
      const std::vector<uint32_t>& prev = prevSentIds[size_t(k)];
      size_t& c = prevCursor[size_t(k)];
      while (c < prev.size() && prev[c] < id) ++c;
      const bool again = layoutValid && c < prev.size() && prev[c] == id;
      std::vector<char>& m = out[size_t(k)];
      Put(m, ShadowHeader{id, again ? 0u : 1u});
      if (again) {
        ShadowState st;
        std::memset(static_cast<void*>(&st), 0, sizeof st);
        const int i = ownedLocal[o];
        if (ownedStale && i >= 0) {
          st.xf = local.xf[size_t(i)];
          st.center = local.center[size_t(i)];
          st.vel = local.vel[size_t(i)];
        } else {
          const Record whole = OwnedRecord(o);
          st.xf = whole.xf;
          st.center = whole.center;
          st.vel = whole.vel;
        }
        Put(m, st);
      } else {
        if (!haveRecord) r = OwnedRecord(o);
        haveRecord = true;
        Put(m, r);
      }
      sentShadows[size_t(k)].push_back(static_cast<int>(o));
      sentIds[size_t(k)].push_back(id);
    }
  }
  prevSentIds.swap(sentIds);  // this step's, for the next
  Round(2);
}

// The rank's bodies (statics, owned, shadows): rebuilt, they are merged in id order; patched
// (PatchLocal), kept rows stay where they are. When the layout is still valid and the same
// shadows came in the same order, last step's arrays are kept: the owned rows already hold the
// bodies' state (Step writes it back), statics do not move, so only the shadows' rows and the
// moving bodies' boxes are written (on one rank, with 16004 circles, rebuilding cost about 1 ms
// a step).
void DistributedWorld::Impl::BuildLocal(Real dt) {
  // The shadow messages' entries (SendShadows' format).
  for (size_t k = 0; k < neighbours.size(); ++k) {
    std::vector<ShadowEntry>& entries = shadowIn[k];
    entries.clear();
    size_t at = 0;
    while (at < in[k].size()) {
      const ShadowHeader h = Take<ShadowHeader>(in[k], at);
      entries.push_back({h.id, h.full != 0, at});
      at += h.full ? sizeof(Record) : sizeof(ShadowState);
      if (at > in[k].size()) throw std::logic_error("DistributedWorld: a shadow message is cut short");
    }
  }
  bool same = layoutValid && !ownedChanged;
  for (size_t k = 0; same && k < neighbours.size(); ++k) {
    same = shadowIn[k].size() == receivedShadows[k].size();
    for (size_t j = 0; same && j < receivedShadows[k].size(); ++j) {
      same = shadowIn[k][j].id == local.slot[size_t(receivedShadows[k][j])];
    }
  }
  if (same) {
    size_t count = 0;
    for (size_t k = 0; k < neighbours.size(); ++k) {
      for (size_t j = 0; j < receivedShadows[k].size(); ++j) {
        WriteShadow(k, shadowIn[k][j], receivedShadows[k][j], dt);
      }
      count += receivedShadows[k].size();
    }
    // The owned rows' boxes were written by the halo pass (the layout was valid then).
    stats.shadowBodies = static_cast<int>(count);
    stats.layoutKept = 1;
    return;
  }
  if (layoutValid) {
    PatchLocal(dt);
    return;
  }
  SyncOwned();  // the local arrays are rebuilt from the records
  sources.clear();
  shadows.clear();
  // Runs each in id order (statics, owned, and every neighbour's shadows, sent in its id order)
  // are merged, not sorted: a sort of 16004 sources was 17 % of a rebuilding step.
  runEnds.clear();
  for (size_t i = 0; i < statics.size(); ++i) sources.push_back({statics[i].id, 0, int(i), -1});
  runEnds.push_back(sources.size());
  for (size_t i = 0; i < owned.size(); ++i) sources.push_back({owned[i].id, 1, int(i), -1});
  runEnds.push_back(sources.size());
  for (size_t k = 0; k < neighbours.size(); ++k) {
    for (const ShadowEntry& e : shadowIn[k]) {
      // Every layout starts again on every rank at once (tiles dealt, a scene or checkpoint
      // loaded), and then every shadow is sent whole.
      if (!e.full) throw std::logic_error("DistributedWorld: a shadow state where its record was needed");
      size_t at = e.at;
      shadows.push_back(Take<Record>(in[k], at));
      sources.push_back({shadows.back().id, 2, int(shadows.size() - 1), int(k)});
    }
    runEnds.push_back(sources.size());
  }
  const auto byId = [](const Source& a, const Source& b) { return a.id < b.id; };
  bool runsSorted = true;
  for (size_t r = 0, from = 0; r < runEnds.size(); from = runEnds[r++]) {
    runsSorted = runsSorted && std::is_sorted(sources.begin() + std::ptrdiff_t(from), sources.begin() + std::ptrdiff_t(runEnds[r]), byId);
  }
  if (runsSorted) {
    for (size_t r = 1; r < runEnds.size(); ++r) {
      std::inplace_merge(sources.begin(), sources.begin() + std::ptrdiff_t(runEnds[r - 1]),
                         sources.begin() + std::ptrdiff_t(runEnds[r]), byId);
    }
  } else {
    std::sort(sources.begin(), sources.end(), byId);
  }
  for (size_t i = 1; i < sources.size(); ++i) {
    if (sources[i].id == sources[i - 1].id) throw std::logic_error("DistributedWorld: a body held twice");
  }
  // Every array sized to the new count (capacity kept: no allocation once warm), then each row
  // written by SetRow. The arrays SetRow leaves alone (aabb aside: below) hold their defaults in
  // every row: nothing in this world writes them (no user data, gravity scale, bullet or compound).
  const size_t n = sources.size();
  local.ForEachArray([n](auto& v) { v.resize(n); });
  localOwned.assign(sources.size(), 0);
  ownedLocal.assign(owned.size(), -1);
  for (auto& r : receivedShadows) r.clear();
  for (size_t i = 0; i < sources.size(); ++i) {
    const Source& s = sources[i];
    const Record& r = s.kind == 0 ? statics[size_t(s.index)] : s.kind == 1 ? owned[size_t(s.index)] : shadows[size_t(s.index)];
    SetRow(local, static_cast<int>(i), r);
    // As the World: a static body's box is made once at creation (dt 0), a moving one's each step.
    local.aabb[i] = s.kind == 1 ? ownedBoxes[size_t(s.index)] : BroadPhaseBox(local, static_cast<int>(i), def, r.type == BodyType::kStatic ? Real(0) : dt);
    if (s.kind == 1) {
      localOwned[i] = 1;
      ownedLocal[size_t(s.index)] = static_cast<int>(i);
    }
  }
  // Shadows were sent in their owner's id order, so walking the id-sorted sources per neighbour
  // gives the order of the neighbour's velocity messages.
  for (size_t i = 0; i < sources.size(); ++i) {
    if (sources[i].kind == 2) receivedShadows[size_t(sources[i].neighbour)].push_back(static_cast<int>(i));
  }
  stats.shadowBodies = static_cast<int>(shadows.size());
  localCustomFilters = 0;
  for (const Filter& f : local.filter) localCustomFilters += f == Filter{} ? 0 : 1;
  localKinematic = 0;
  pairMovable.resize(n);
  for (size_t i = 0; i < n; ++i) {
    localKinematic += local.type[i] == BodyType::kKinematic ? 1 : 0;
    pairMovable[i] = local.dynamic[i] & localOwned[i];
  }
  layoutValid = true;
  rowsInIdOrder = true;
  rowOfIdValid = false;
  ownedChanged = false;
}

// BuildLocal when last step's `local` is still laid out for this rank's neighbours but bodies
// left or arrived, or other shadows came: the rows that stay (statics and staying owned bodies,
// whose rows hold their newest state and, from the halo pass, this step's box) stay where they
// are; the arrivals and every shadow are written from records into the rows that were freed (last
// step's shadows, bodies that left), then appended. Where more rows were freed than are needed,
// the last kept rows move down into the gaps. Rows are thus in no particular order: FindContacts
// orients every pair and orders the contacts by body id, so the arithmetic is a rebuild's.
// Measured (2 ranks, 16004 circles each, amd-epyc-2c): merging by id instead copied every kept
// row of every array into a second set of arrays (413 bytes a row, 6.6 MB a step), 18 % of the
// step's profile: bodies cross or the shadow set changes nearly every step.
void DistributedWorld::Impl::PatchLocal(Real dt) {
  // Only the rows that change are visited (the freed ones, the moved ones, the written ones) and
  // the owned list once: every pass over all rows cost about 8 instructions a row, 1.0M of a
  // 2-rank circle-stress step's instructions before.
  const size_t before = size_t(local.Count());
  // Freed: the rows of the bodies that left (Migrate) and of last step's shadows that came whole
  // or not at all; a shadow sent again as a ShadowState keeps its row (it holds the body's
  // constant data). Both lists are in id order.
  size_t shadowCount = 0, newShadows = 0;
  shadowKeptRow.clear();
  for (size_t k = 0; k < neighbours.size(); ++k) {
    const std::vector<int>& old = receivedShadows[k];
    size_t j = 0;
    for (const ShadowEntry& e : shadowIn[k]) {
      int row = -1;
      if (!e.full) {
        while (j < old.size() && local.slot[size_t(old[j])] < e.id) freedRows.push_back(old[j++]);
        if (j == old.size() || local.slot[size_t(old[j])] != e.id) {
          throw std::logic_error("DistributedWorld: a shadow state for a body not held");
        }
        row = old[j++];
      } else {
        ++newShadows;
      }
      shadowKeptRow.push_back(row);
    }
    while (j < old.size()) freedRows.push_back(old[j++]);
    shadowCount += shadowIn[k].size();
  }
  std::sort(freedRows.begin(), freedRows.end());
  keepRow.assign(before, 1);
  const auto uncount = [this](size_t i) {
    localCustomFilters -= local.filter[i] == Filter{} ? 0 : 1;
    localKinematic -= local.type[i] == BodyType::kKinematic ? 1 : 0;
  };
  for (int i : freedRows) {
    keepRow[size_t(i)] = 0;
    uncount(size_t(i));
  }
  const size_t arriving = arrivals.size();  // Migrate marked each in ownedLocal (-1 - its index)
  const size_t kept = before - freedRows.size();
  const size_t n = kept + arriving + newShadows;
  // Free rows below n, ascending; kept rows at or above n move into the first of them.
  freeRows.clear();
  for (int i : freedRows) {
    if (size_t(i) < n) freeRows.push_back(i);
  }
  for (size_t i = before; i < n; ++i) freeRows.push_back(static_cast<int>(i));
  moves.clear();
  size_t nextFree = 0;
  for (size_t i = n; i < before; ++i) {
    if (!keepRow[i]) continue;
    moves.push_back({static_cast<int>(i), freeRows[nextFree++]});
    uncount(i);  // counted again at its new row, with every written row
  }
  // No body twice: an arriving or shadow id must not be held by a row that stays (rowOfId maps
  // every row before the patch while valid; the written rows are checked against each other
  // below).
  if (rowOfIdValid) {
    const auto heldByKept = [&](uint32_t id) {
      if (id >= rowOfId.size()) return false;
      const size_t q = size_t(rowOfId[id]);
      return q < before && keepRow[q] && local.slot[q] == id;
    };
    for (const Record& r : arrivals) {
      if (heldByKept(r.id)) throw std::logic_error("DistributedWorld: a body held twice");
    }
    for (size_t k = 0; k < neighbours.size(); ++k) {
      for (const ShadowEntry& e : shadowIn[k]) {
        if (e.full && heldByKept(e.id)) throw std::logic_error("DistributedWorld: a body held twice");
      }
    }
  }
  const size_t size = std::max(before, n);
  local.ForEachArray([&](auto& v) {
    v.resize(size);
    for (const auto& m : moves) v[size_t(m.second)] = v[size_t(m.first)];
    v.resize(n);
  });
  // localOwned moved with the other arrays; the freed rows below n are written below.
  localOwned.resize(size);
  for (const auto& m : moves) localOwned[size_t(m.second)] = localOwned[size_t(m.first)];
  localOwned.resize(n);
  for (int i : freeRows) localOwned[size_t(i)] = 0;
  for (size_t o = 0; o < ownedLocal.size(); ++o) {
    int& i = ownedLocal[o];
    if (i >= 0) {
      if (size_t(i) >= n) i = MovedTo(i);
    } else {
      // An arrival: its record, then its row (OwnedRecord reads the record through ownedLocal).
      const Record r = OwnedRecord(o);
      const int row = freeRows[nextFree++];
      SetRow(local, row, r);
      local.aabb[size_t(row)] = BoxOf(r, dt);
      i = row;
    }
    localOwned[size_t(i)] = 1;
  }
  for (size_t k = 0, e = 0; k < neighbours.size(); ++k) {
    receivedShadows[k].clear();
    for (const ShadowEntry& entry : shadowIn[k]) {
      int row = shadowKeptRow[e++];
      if (row < 0) {
        row = freeRows[nextFree++];
      } else if (size_t(row) >= n) {
        row = MovedTo(row);
      }
      WriteShadow(k, entry, row, dt);
      receivedShadows[k].push_back(row);
    }
  }
  if (nextFree != freeRows.size()) throw std::logic_error("DistributedWorld: rows left unfilled");
  pairMovable.resize(n);
  for (int i : freeRows) {
    localCustomFilters += local.filter[size_t(i)] == Filter{} ? 0 : 1;
    localKinematic += local.type[size_t(i)] == BodyType::kKinematic ? 1 : 0;
    pairMovable[size_t(i)] = local.dynamic[size_t(i)] & localOwned[size_t(i)];
  }
  if (rowOfIdValid) {
    for (int i : freeRows) {
      const uint32_t id = local.slot[size_t(i)];
      if (id >= rowOfId.size()) rowOfId.resize(size_t(id) + 1);
      idBound = std::max(idBound, id + 1);
      rowOfId[id] = i;
    }
    for (int i : freeRows) {
      if (rowOfId[local.slot[size_t(i)]] != i) throw std::logic_error("DistributedWorld: a body held twice");
    }
  }
  // Last step's contacts name their bodies by row: renumbered to the patched rows, they are
  // recycled as after a kept layout (FindContacts); those with a freed row (a body that left, a
  // shadow not sent again or sent whole) go, and so do one-point manifolds, which the pair loop
  // never recycles (circle stress has only those: copying them was 5 us a step).
  if (rankSolver && def.contactRecycleDistance > 0 && def.effects.warmStarting) {
    size_t kept = 0;
    for (size_t c = 0; c < contacts.size(); ++c) {
      const int a = contacts[c].a, b = contacts[c].b;
      if (contacts[c].manifold.pointCount != 2 || !keepRow[size_t(a)] || !keepRow[size_t(b)]) continue;
      if (kept != c) contacts[kept] = contacts[c];
      contacts[kept].a = size_t(a) >= n ? MovedTo(a) : a;
      contacts[kept].b = size_t(b) >= n ? MovedTo(b) : b;
      ++kept;
    }
    contacts.resize(kept);
    contactsRenumbered = true;
  }
  freedRows.clear();
  stats.shadowBodies = static_cast<int>(shadowCount);
  stats.layoutPatched = 1;
  stats.rowsMoved = static_cast<int>(moves.size());
  rowsInIdOrder = false;
  ownedChanged = false;
}

// The rows back in id order, as a rebuild lays them, between steps. Each patch writes arrivals
// and new shadows into freed rows and moves the last rows into the gaps, so the owned bodies'
// rows scatter over a long run and every pass in owned order misses the cache more: at 2 ranks x
// 16004 circles the halo pass took 0.175 ms a step after 100 steps and 0.20-0.21 after 5000
// (1300 of the owned list's 16000 rows out of sequence by then). Reordering moves every row of
// every array (about 2 ms at 16000 rows), so it waits until a 16th of the owned bodies' rows are
// out of sequence (checked every 64 steps; at this scene's rate of crossings, every 1500-2000
// steps). Nothing in the arithmetic depends on where rows lie (FindContacts orders everything by
// id), so it changes no bit; the row numbers kept between steps (the owned list's, the shadows',
// last step's contacts for recycling, rowOfId) are renumbered.
void DistributedWorld::Impl::OrderRows(bool reverse) {
  const size_t n = size_t(local.Count());
  rowOrder.resize(n);
  for (size_t i = 0; i < n; ++i) rowOrder[i] = static_cast<int>(i);
  std::sort(rowOrder.begin(), rowOrder.end(), [this, reverse](int a, int b) {
    return reverse ? local.slot[size_t(a)] > local.slot[size_t(b)] : local.slot[size_t(a)] < local.slot[size_t(b)];
  });
  newRowOf.resize(n);
  for (size_t i = 0; i < n; ++i) newRowOf[size_t(rowOrder[i])] = static_cast<int>(i);
  const auto permute = [&](auto& v) {
    std::remove_reference_t<decltype(v)> ordered(v.size());
    for (size_t i = 0; i < n; ++i) ordered[i] = std::move(v[size_t(rowOrder[i])]);
    v.swap(ordered);
  };
  local.ForEachArray(permute);
  permute(localOwned);
  permute(pairMovable);
  for (int& i : ownedLocal) {
    if (i < 0) throw std::logic_error("DistributedWorld: an owned body without a row between steps");
    i = newRowOf[size_t(i)];
  }
  for (auto& rows : receivedShadows) {
    for (int& i : rows) i = newRowOf[size_t(i)];
  }
  for (Contact& c : contacts) {
    c.a = newRowOf[size_t(c.a)];
    c.b = newRowOf[size_t(c.b)];
  }
  if (rowOfIdValid) {
    for (size_t i = 0; i < n; ++i) rowOfId[local.slot[i]] = static_cast<int32_t>(i);
  }
  rowsInIdOrder = !reverse;
}

// The contacts of the rank's own bodies: broad phase over everything it holds, pairs without an
// owned body dropped (their owners compute them), then the World's narrow phase, key order and
// warm-start impulses.
void DistributedWorld::Impl::FindContacts(Real dt) {
  // Rows out of id order (patched: PatchLocal): each body's row by id, for the contacts' way back
  // from id order; a body held twice is a bookkeeping error.
  const int count = local.Count();
  if (!rowsInIdOrder && !rowOfIdValid) {
    idBound = 0;
    for (int i = 0; i < count; ++i) idBound = std::max(idBound, local.slot[size_t(i)] + 1);
    if (rowOfId.size() < idBound) rowOfId.resize(idBound);
    for (int i = 0; i < count; ++i) rowOfId[local.slot[size_t(i)]] = i;
    for (int i = 0; i < count; ++i) {
      if (rowOfId[local.slot[size_t(i)]] != i) throw std::logic_error("DistributedWorld: a body held twice");
    }
    rowOfIdValid = true;
  }
  const uint32_t idLimit = idBound;
  // Only the owned dynamic rows are movable to the broad phase: a shadow, like a static body, is
  // then paired only with a movable body, which is owned, and the pairs without an owned body
  // (their owners find them) are never made, and no pass over all the pairs drops them: 2 ranks x
  // 16004 circles 1.53 -> 1.50 ms a step (docs/notes/distributed.md), the same bits.
  // Not where the rank holds a kinematic body: an owned kinematic body's pair with a dynamic shadow
  // is made only by the shadow being movable.
  const std::vector<uint8_t>* movable = &local.dynamic;
  bool ownedOnly = true;  // every pair has an owned body
  if (stats.shadowBodies > 0) {
    if (localKinematic == 0) {
      movable = &pairMovable;  // kept by BuildLocal and PatchLocal
    } else {
      ownedOnly = false;
    }
  }
  broadPhase->FindPairs(local.aabb, *movable, pairs, *run);
  // Without a custom filter, and where every pair has an owned body, all of them are kept.
  const bool keepAll = ownedOnly && localCustomFilters == 0;
  ownPairs.clear();
  // The World's collision filter (Box2D's rule) on the same pairs; its compaction keeps order.
  const std::vector<Filter>& f = local.filter;
  for (size_t k = 0; !keepAll && k < pairs.size(); ++k) {
    const CandidatePair p = pairs[k];
    if (!localOwned[size_t(p.a)] && !localOwned[size_t(p.b)]) continue;
    if (!ShouldCollide(f[size_t(p.a)], f[size_t(p.b)])) continue;
    ownPairs.push_back(p);
  }
  if (keepAll) ownPairs.swap(pairs);
  // Every pair oriented as in one process, where rows are in id order: the lower id first.
  if (!rowsInIdOrder) {
    for (CandidatePair& p : ownPairs) {
      if (local.slot[size_t(p.a)] > local.slot[size_t(p.b)]) std::swap(p.a, p.b);
    }
  }
  // kSoftStep recycles last step's manifolds as the World does (contactRecycleDistance: a pair
  // that barely moved keeps its manifold), where last step's rows are this step's (layoutKept)
  // or the patch renumbered the contacts to its rows: the old contacts name bodies by row.
  // Without it a resting base-20 pyramid's apex drifted 0.013 m in 59 s on one rank, as the
  // World's does without it (0.0014 m with it). After a rebuild the source is empty: the narrow
  // phase still records what the next step's recycling compares with.
  const RecycleSource* recycle = nullptr;
  const bool contactsRenumbered = std::exchange(this->contactsRenumbered, false);
  if (rankSolver && def.contactRecycleDistance > 0 && def.effects.warmStarting) {
    lastContacts.clear();
    if (stats.layoutKept || contactsRenumbered) lastContacts.swap(contacts);
    // The pair loop looks for a pair within its body a's run by ascending row b. Rows out of id
    // order (a patch since the last rebuild), the runs, in id order, are put in row order (each a
    // few contacts): else whether a pair is recycled depended on how the rows lay.
    if (!rowsInIdOrder) {
      for (size_t from = 0, to = 0; from < lastContacts.size(); from = to) {
        to = from + 1;
        while (to < lastContacts.size() && lastContacts[to].a == lastContacts[from].a) ++to;
        for (size_t i = from + 1; i < to; ++i) {
          for (size_t j = i; j > from && lastContacts[j - 1].b > lastContacts[j].b; --j) std::swap(lastContacts[j - 1], lastContacts[j]);
        }
      }
    }
    // Stale entries stay: the pair loop takes one only where it starts its body's run.
    if (recycleFirst.size() < size_t(count)) recycleFirst.resize(size_t(count), -1);
    for (size_t i = 0; i < lastContacts.size(); ++i) {
      if (i == 0 || lastContacts[i - 1].a != lastContacts[i].a) recycleFirst[size_t(lastContacts[i].a)] = int32_t(i);
    }
    recycleSource = {lastContacts.data(), static_cast<int>(lastContacts.size()), recycleFirst.data(), def.contactRecycleDistance};
    recycle = &recycleSource;
  }
  // The World's narrow phase, then its contact sort on the bodies' ids (per-worker lists merged
  // in key order): the same contacts in the same order for any thread and rank count.
  workerContacts.Reset(run->Workers());
  run->For(Stage::kNarrowPhase, static_cast<int>(ownPairs.size()), run->MinHeavyItems(), [&](int begin, int end, int worker) {
    CollidePairs(local, def, dt, std::span<const CandidatePair>(ownPairs).subspan(size_t(begin), size_t(end - begin)),
                 workerContacts[worker], recycle);
  });
  if (rowsInIdOrder) {
    sorter.Sort(*run, count, workerContacts, contacts, nullptr);
  } else {
    for (int w = 0; w < workerContacts.Count(); ++w) {
      for (Contact& c : workerContacts[w]) {
        c.a = static_cast<int32_t>(local.slot[size_t(c.a)]);
        c.b = static_cast<int32_t>(local.slot[size_t(c.b)]);
      }
    }
    sorter.Sort(*run, static_cast<int>(idLimit), workerContacts, contacts, nullptr);
    for (Contact& c : contacts) {
      c.a = rowOfId[size_t(c.a)];
      c.b = rowOfId[size_t(c.b)];
    }
  }
  if (!def.effects.warmStarting) return;
  // ContactCache::Restore's rule: the entry of the same pair, points matched by feature id. The
  // contacts are in id-pair order, as the cache is: one walk through both.
  auto it = cache.begin();
  for (Contact& c : contacts) {
    const uint64_t key = PairKey(local.slot[size_t(c.a)], local.slot[size_t(c.b)]);
    while (it != cache.end() && it->key < key) ++it;
    if (it == cache.end()) break;
    if (it->key != key) continue;
    for (int k = 0; k < c.manifold.pointCount; ++k) {
      ManifoldPoint& p = c.manifold.points[k];
      for (int j = 0; j < it->pointCount; ++j) {
        if (it->ids[j] == p.id) {
          p.normalImpulse = it->normalImpulse[j];
          p.tangentImpulse = it->tangentImpulse[j];
          break;
        }
      }
    }
  }
}

// A solve round, in two halves so that rows away from the boundary are solved while it travels:
// the velocities and pseudo velocities (and after warm starting, the contact counts) of every
// owned body that is a shadow elsewhere replace that shadow's partial ones there. Each message's
// size is known (one record per shadow, in the order both sides hold), so it is received
// directly, with no probe.
void DistributedWorld::Impl::PostVelocities(int tag) {
  ClearOut();
  const std::vector<int32_t>& count = solve.Counts();
  const std::vector<BodyVelocity>& pseudo = solve.Pseudo();
  for (size_t k = 0; k < neighbours.size(); ++k) {
    for (const int i : sentRows[k]) {
      Put(out[k], VelocityRecord{local.vel[size_t(i)], pseudo[size_t(i)], count[size_t(i)]});
    }
  }
  PostShadowRound(tag, sizeof(VelocityRecord));
}

void DistributedWorld::Impl::CompleteVelocities(bool counts) {
  CompleteShadowRound("velocity");
  std::vector<int32_t>& count = solve.Counts();
  std::vector<BodyVelocity>& pseudo = solve.Pseudo();
  for (size_t k = 0; k < neighbours.size(); ++k) {
    size_t at = 0;
    for (int i : receivedShadows[k]) {
      const VelocityRecord v = Take<VelocityRecord>(in[k], at);
      local.vel[size_t(i)] = v.vel;
      pseudo[size_t(i)] = v.pseudo;
      if (counts) count[size_t(i)] = v.count;
    }
  }
}

// A round of one record per shadow (the solvers' exchanges): out[k], packed by the caller, goes to
// neighbours[k]; in[k] is sized for its shadows here, so it is received directly, with no probe.
void DistributedWorld::Impl::PostShadowRound(int tag, size_t recordSize) {
  const size_t n = neighbours.size();
  requests.assign(2 * n, MPI_REQUEST_NULL);
  for (size_t k = 0; k < n; ++k) {
    in[k].resize(receivedShadows[k].size() * recordSize);
    MPI_Irecv(in[k].data(), static_cast<int>(in[k].size()), MPI_BYTE, neighbours[k], tag, comm, &requests[n + k]);
    MPI_Isend(out[k].data(), static_cast<int>(out[k].size()), MPI_BYTE, neighbours[k], tag, comm, &requests[k]);
    stats.bytesSent += static_cast<int64_t>(out[k].size());
  }
}

// Waits for the round (timed as wait) and checks that every message holds one record per shadow.
void DistributedWorld::Impl::CompleteShadowRound(const char* what) {
  const auto waitFrom = std::chrono::steady_clock::now();
  statuses.resize(requests.size());
  MPI_Waitall(static_cast<int>(requests.size()), requests.data(), statuses.data());
  stats.waitMs += std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - waitFrom).count();
  ++stats.rounds;
  const size_t n = neighbours.size();
  for (size_t k = 0; k < n; ++k) {
    int got = 0;
    MPI_Get_count(&statuses[n + k], MPI_BYTE, &got);
    if (size_t(got) != in[k].size()) {
      throw std::logic_error(std::string("DistributedWorld: a ") + what + " message does not match the shadows");
    }
  }
}

// The soft step's round (kSoftStep), after each pass of a sub-step: every owned body that is a
// shadow elsewhere sends its solver state, which replaces the shadow's there; a shadow's own state
// holds only this rank's rows. A body in no row here has no state: it sends a mark and the other
// side keeps its own. Only the velocity travels (16 bytes) unless a pass moved bodies through
// their rows since the last round (rowsMoved: the bounces): the sub-steps' motion so far (dp, dq)
// is then the same bits on both sides, as both integrate it from the same velocities. At 2 x 16004
// circles the 150 whole states (36 bytes each) were 5.4 KB, past Open MPI's 4 KB eager limit for
// shared memory: 3.2 us a round for both directions against 0.9 us below it (9 rounds a step).
void DistributedWorld::Impl::ExchangeStates(std::span<SolverBody> states, std::span<const uint8_t> inRows, bool rowsMoved) {
  const auto from = std::chrono::steady_clock::now();
  if (rowsMoved || checkShadowMotion) {
    ExchangeStateRecords<true>(states, inRows, checkShadowMotion && !rowsMoved);
  } else {
    ExchangeStateRecords<false>(states, inRows, false);
  }
  exchangeInSolveMs += std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - from).count();
}

template <bool kWhole>
void DistributedWorld::Impl::ExchangeStateRecords(std::span<SolverBody> states, std::span<const uint8_t> inRows, bool sameMotion) {
  struct WholeState {
    SolverBody state;
    int32_t held;
  };
  struct VelocityState {
    Vec2 v;
    Real w;
    int32_t held;
  };
  using StateRecord = std::conditional_t<kWhole, WholeState, VelocityState>;
  static_assert(std::is_trivially_copyable_v<StateRecord>);
  // Packed in place (a resize per record was about half of this function's time).
  for (size_t k = 0; k < neighbours.size(); ++k) {
    out[k].resize(sentRows[k].size() * sizeof(StateRecord));
    char* to = out[k].data();
    for (const int row : sentRows[k]) {
      const size_t i = size_t(row);
      StateRecord r{};
      r.held = inRows[i] ? 1 : 0;
      if constexpr (kWhole) {
        if (r.held) r.state = states[i];
      } else {
        if (r.held) {
          r.v = states[i].v;
          r.w = states[i].w;
        }
      }
      std::memcpy(to, &r, sizeof r);
      to += sizeof r;
    }
  }
  PostShadowRound(5, sizeof(StateRecord));
  CompleteShadowRound("state");
  for (size_t k = 0; k < neighbours.size(); ++k) {
    const char* from = in[k].data();  // CompleteShadowRound checked the size: one record per shadow
    for (int i : receivedShadows[k]) {
      StateRecord r;
      std::memcpy(&r, from, sizeof r);
      from += sizeof r;
      if (!r.held || !inRows[size_t(i)]) continue;
      if constexpr (kWhole) {
        SolverBody& st = states[size_t(i)];
        if (sameMotion && (std::memcmp(&st.dp, &r.state.dp, sizeof st.dp) != 0 || std::memcmp(&st.dq, &r.state.dq, sizeof st.dq) != 0)) {
          ++motionMismatches;  // CheckCounts throws on every rank alike
        }
        st = r.state;
      } else {
        states[size_t(i)].v = r.v;
        states[size_t(i)].w = r.w;
      }
    }
  }
}

// The solve's rows split by whether they touch a shadow (whose velocity comes from its owner
// each iteration): interior rows first, boundary rows after the round.
void DistributedWorld::Impl::SplitRows() {
  interiorRows.clear();
  boundaryRows.clear();
  for (size_t c = 0; c < solve.RowCount(); ++c) {
    const auto [a, b] = solve.RowBodies(c);
    const auto shadow = [&](int32_t i) { return !localOwned[size_t(i)] && local.type[size_t(i)] != BodyType::kStatic; };
    (shadow(a) || shadow(b) ? boundaryRows : interiorRows).push_back(static_cast<int32_t>(c));
  }
}

// As ContactCache::Store: the contacts that carry an impulse, by id pair.
void DistributedWorld::Impl::StoreCache() {
  cache.clear();
  if (!def.effects.warmStarting) return;
  for (const Contact& c : contacts) {
    const Manifold& m = c.manifold;
    bool carries = false;
    for (int k = 0; k < m.pointCount; ++k) carries = carries || m.points[k].normalImpulse != 0 || m.points[k].tangentImpulse != 0;
    if (!carries) continue;
    CacheEntry e;
    std::memset(static_cast<void*>(&e), 0, sizeof e);
    e.key = PairKey(local.slot[size_t(c.a)], local.slot[size_t(c.b)]);
    e.pointCount = m.pointCount;
    for (int k = 0; k < m.pointCount; ++k) {
      e.ids[k] = m.points[k].id;
      e.normalImpulse[k] = m.points[k].normalImpulse;
      e.tangentImpulse[k] = m.points[k].tangentImpulse;
    }
    cache.push_back(e);
  }
}

// Nothing lost, nothing duplicated: the global count of owned bodies and the sum of their mixed
// ids (exact integer sums, modulo 2^64) against the loaded scene's; and, under
// QUADRANT_CHECK_SHADOW_MOTION, no shadow whose motion moved apart from its owner's.
void DistributedWorld::Impl::CheckCounts() {
  int64_t cost = 0;
  for (int64_t c : tileCost) cost += c;
  const size_t count = OwnedCount();
  uint64_t mine[4] = {uint64_t(count), 0, uint64_t(cost), motionMismatches};
  for (size_t o = 0; o < count; ++o) mine[1] += MixId(OwnedId(o));
  // One collective for the sums and the maximum (each rank's four numbers to every rank).
  countsAll.resize(4 * size_t(size));
  MPI_Allgather(mine, 4, MPI_UINT64_T, countsAll.data(), 4, MPI_UINT64_T, comm);
  uint64_t global[4] = {0, 0, 0, 0};
  int64_t most = 0;
  for (int r = 0; r < size; ++r) {
    for (int j = 0; j < 4; ++j) global[j] += countsAll[4 * size_t(r) + size_t(j)];
    most = std::max(most, int64_t(countsAll[4 * size_t(r) + 2]));
  }
  Require(global[3] == 0, [&] {
    return "DistributedWorld: " + std::to_string(global[3]) +
           " shadow state(s) moved apart from their owners' between the soft step's rounds (QUADRANT_CHECK_SHADOW_MOTION)";
  });
  stats.imbalance = global[2] > 0 ? double(most) / (double(global[2]) / size) : 1.0;
  Require(global[0] == expectedCount && global[1] == expectedChecksum, [&] {
    return "DistributedWorld: body bookkeeping broken: " + std::to_string(global[0]) + " bodies owned, " +
           std::to_string(expectedCount) + " loaded (or the id checksum differs)";
  });
}

std::vector<BodyState> DistributedWorld::GatherStates() const {
  impl_->SyncOwned();  // the records are read whole (the world's state itself does not change)
  const Impl& w = *impl_;
  std::vector<BodyState> mine;
  auto state = [](const Record& r) {
    BodyState s;
    s.id = r.id;
    s.position = r.xf.p;
    s.rotation = r.xf.q;
    s.linearVelocity = r.vel.v;
    s.angularVelocity = r.vel.w;
    s.mass = r.mass;
    return s;
  };
  for (const Record& r : w.owned) mine.push_back(state(r));
  const int bytes = static_cast<int>(mine.size() * sizeof(BodyState));
  std::vector<int> counts(size_t(w.size)), displs(size_t(w.size));
  MPI_Allgather(&bytes, 1, MPI_INT, counts.data(), 1, MPI_INT, w.comm);
  int total = 0;
  for (int r = 0; r < w.size; ++r) {
    displs[size_t(r)] = total;
    total += counts[size_t(r)];
  }
  std::vector<BodyState> all(size_t(total) / sizeof(BodyState));
  MPI_Allgatherv(mine.data(), bytes, MPI_BYTE, all.data(), counts.data(), displs.data(), MPI_BYTE, w.comm);
  for (const Record& r : w.statics) all.push_back(state(r));
  std::sort(all.begin(), all.end(), [](const BodyState& a, const BodyState& b) { return a.id < b.id; });
  return all;
}

uint64_t DistributedWorld::StateHash() const {
  BitHash h;
  for (const BodyState& s : GatherStates()) {
    h.Mix(s.position.x);
    h.Mix(s.position.y);
    h.Mix(s.rotation.c);
    h.Mix(s.rotation.s);
    h.Mix(s.linearVelocity.x);
    h.Mix(s.linearVelocity.y);
    h.Mix(s.angularVelocity);
  }
  return h.Value();
}

// ---- checkpoints ------------------------------------------------------------------------------
//
// Layout: magic, sizeof(Real), sizeof(Record), sizeof(CacheEntry), body count, entry count, the
// records in id order, the entries in key order, then FNV-1a of everything before it. Warm-start
// entries are written once per contact (two ranks hold equal copies of a boundary contact's).

namespace {

constexpr char kCheckpointMagic[8] = {'Q', 'D', 'C', 'K', 'P', 'T', '0', '1'};

uint64_t Fnv(const char* data, size_t n) {
  uint64_t h = 0xcbf29ce484222325ull;
  for (size_t i = 0; i < n; ++i) {
    h ^= static_cast<unsigned char>(data[i]);
    h *= 0x100000001b3ull;
  }
  return h;
}

// All ranks' bytes on rank 0, in rank order.
std::vector<char> GatherBytes(const std::vector<char>& mine, int rank, int size, MPI_Comm comm) {
  const int bytes = static_cast<int>(mine.size());
  std::vector<int> counts(size_t(size), 0), displs(size_t(size), 0);
  MPI_Gather(&bytes, 1, MPI_INT, counts.data(), 1, MPI_INT, 0, comm);
  int total = 0;
  for (int r = 0; r < size; ++r) {
    displs[size_t(r)] = total;
    total += counts[size_t(r)];
  }
  std::vector<char> all(rank == 0 ? size_t(total) : 0);
  MPI_Gatherv(mine.data(), bytes, MPI_BYTE, all.data(), counts.data(), displs.data(), MPI_BYTE, 0, comm);
  return all;
}

}  // namespace

void DistributedWorld::WriteCheckpoint(const std::string& path) const {
  impl_->SyncOwned();
  const Impl& w = *impl_;
  Require(w.loaded, "DistributedWorld::WriteCheckpoint: Load a scene first");
  std::vector<char> mine;
  for (const Record& r : w.owned) Put(mine, r);
  const std::vector<char> records = GatherBytes(mine, w.rank, w.size, w.comm);
  mine.clear();
  for (const CacheEntry& e : w.cache) Put(mine, e);
  const std::vector<char> entries = GatherBytes(mine, w.rank, w.size, w.comm);
  int ok = 1;
  if (w.rank == 0) {
    std::vector<Record> bodies(w.statics);
    for (size_t at = 0; at < records.size();) bodies.push_back(Take<Record>(records, at));
    std::sort(bodies.begin(), bodies.end(), [](const Record& a, const Record& b) { return a.id < b.id; });
    std::vector<CacheEntry> cache;
    for (size_t at = 0; at < entries.size();) cache.push_back(Take<CacheEntry>(entries, at));
    std::stable_sort(cache.begin(), cache.end(), [](const CacheEntry& a, const CacheEntry& b) { return a.key < b.key; });
    cache.erase(std::unique(cache.begin(), cache.end(), [](const CacheEntry& a, const CacheEntry& b) { return a.key == b.key; }),
                cache.end());
    std::vector<char> file(kCheckpointMagic, kCheckpointMagic + sizeof kCheckpointMagic);
    Put(file, uint32_t(sizeof(Real)));
    Put(file, uint32_t(sizeof(Record)));
    Put(file, uint32_t(sizeof(CacheEntry)));
    Put(file, uint64_t(bodies.size()));
    Put(file, uint64_t(cache.size()));
    for (const Record& r : bodies) Put(file, r);
    for (const CacheEntry& e : cache) Put(file, e);
    Put(file, Fnv(file.data(), file.size()));
    std::FILE* f = std::fopen(path.c_str(), "wb");
    ok = f != nullptr && std::fwrite(file.data(), 1, file.size(), f) == file.size();
    if (f != nullptr) ok = (std::fclose(f) == 0) && ok;
  }
  MPI_Bcast(&ok, 1, MPI_INT, 0, w.comm);
  Require(ok != 0, "DistributedWorld::WriteCheckpoint: cannot write '" + path + "'");
}

void DistributedWorld::ReadCheckpoint(const std::string& path) {
  Impl& w = *impl_;
  // Every rank reads and checks the file itself; the verdicts are reduced so all ranks agree.
  std::string error;
  std::vector<char> file;
  if (std::FILE* f = std::fopen(path.c_str(), "rb")) {
    char chunk[65536];
    size_t n;
    while ((n = std::fread(chunk, 1, sizeof chunk, f)) > 0) file.insert(file.end(), chunk, chunk + n);
    std::fclose(f);
  } else {
    error = "cannot open '" + path + "'";
  }
  std::vector<Record> statics, owned;
  std::vector<CacheEntry> cache;
  std::vector<Vec2> moving;  // the moving bodies' centres, for the deal
  size_t recordsAt = 0;
  uint64_t count = 0, checksum = 0;
  const size_t header = sizeof kCheckpointMagic + 3 * sizeof(uint32_t) + 2 * sizeof(uint64_t);
  if (error.empty()) {
    if (file.size() < header + sizeof(uint64_t) || std::memcmp(file.data(), kCheckpointMagic, sizeof kCheckpointMagic) != 0) {
      error = "'" + path + "' is not a Quadrant checkpoint (or is truncated before its header ends)";
    }
  }
  if (error.empty()) {
    size_t at = sizeof kCheckpointMagic;
    const uint32_t realSize = Take<uint32_t>(file, at), recordSize = Take<uint32_t>(file, at),
                   entrySize = Take<uint32_t>(file, at);
    const uint64_t bodies = Take<uint64_t>(file, at), entries = Take<uint64_t>(file, at);
    if (realSize != sizeof(Real) || recordSize != sizeof(Record) || entrySize != sizeof(CacheEntry)) {
      error = "'" + path + "' was written by another build (record sizes differ)";
    } else if (bodies > (uint64_t(1) << 31) || entries > (uint64_t(1) << 40) ||
               file.size() != header + bodies * sizeof(Record) + entries * sizeof(CacheEntry) + sizeof(uint64_t)) {
      error = "'" + path + "' is truncated or has trailing bytes (size " + std::to_string(file.size()) + ")";
    } else {
      size_t end = file.size() - sizeof(uint64_t);
      const uint64_t stored = Take<uint64_t>(file, end);
      if (stored != Fnv(file.data(), file.size() - sizeof(uint64_t))) {
        error = "'" + path + "' is corrupt (checksum mismatch)";
      } else {
        recordsAt = at;
        for (uint64_t i = 0; i < bodies && error.empty(); ++i) {
          const Record r = Take<Record>(file, at);
          if (r.id != i || !IsFinite(r.center) || !IsFinite(r.vel.v)) error = "'" + path + "' holds a malformed body";
          if (r.type == BodyType::kStatic) {
            statics.push_back(r);
          } else {
            ++count;
            checksum += MixId(r.id);
            moving.push_back(r.center);
          }
        }
        at = recordsAt + size_t(bodies) * sizeof(Record);
        for (uint64_t i = 0; i < entries; ++i) cache.push_back(Take<CacheEntry>(file, at));
      }
    }
  }
  const int bad = error.empty() ? 0 : 1;
  int anyBad = 0;
  MPI_Allreduce(&bad, &anyBad, 1, MPI_INT, MPI_MAX, w.comm);
  Require(anyBad == 0, "DistributedWorld::ReadCheckpoint: " +
                           (error.empty() ? std::string("another rank could not read the checkpoint") : error));
  // The tiles dealt by the bodies in each, as Load deals them; then this rank's bodies.
  std::vector<int> tileOwner = w.Deal(w.BodyCost(moving));
  for (size_t at = recordsAt, i = 0; i < size_t(count) + statics.size(); ++i) {
    const Record r = Take<Record>(file, at);
    if (r.type != BodyType::kStatic && tileOwner[size_t(w.TileX(r.center.x) + w.TileY(r.center.y) * w.dist.tilesX)] == w.rank) {
      owned.push_back(r);
    }
  }
  // Only the entries of this rank's contacts: those touching an owned body.
  std::vector<uint32_t> ids;
  for (const Record& r : owned) ids.push_back(r.id);
  std::erase_if(cache, [&](const CacheEntry& e) {
    return !std::binary_search(ids.begin(), ids.end(), uint32_t(e.key >> 32)) &&
           !std::binary_search(ids.begin(), ids.end(), uint32_t(e.key));
  });
  w.tileOwner.swap(tileOwner);
  w.FindNeighbours();
  w.statics.swap(statics);
  w.owned.swap(owned);
  w.cache.swap(cache);
  w.layoutValid = false;
  w.ownedStale = false;
  w.expectedCount = count;
  w.expectedChecksum = checksum;
  w.loaded = true;
  std::fill(w.tileCost.begin(), w.tileCost.end(), 0);
  w.CheckCounts();
}

void DistributedWorld::Rebalance() {
  Require(impl_->loaded, "DistributedWorld::Rebalance: Load a scene first");
  impl_->Rebalance(true);
  impl_->CheckCounts();
}

std::vector<int> DistributedWorld::TileOwners() const { return impl_->tileOwner; }

int DistributedWorld::Rank() const { return impl_->rank; }
int DistributedWorld::Size() const { return impl_->size; }
const DistributedStats& DistributedWorld::GetStats() const { return impl_->stats; }

std::vector<uint32_t> DistributedWorld::OwnedIds() const {
  std::vector<uint32_t> ids;
  for (size_t o = 0; o < impl_->OwnedCount(); ++o) ids.push_back(impl_->OwnedId(o));
  return ids;
}

}  // namespace quadrant
