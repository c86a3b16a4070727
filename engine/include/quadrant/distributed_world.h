// Quadrant over MPI: a world split among processes (ranks) by fixed world-space tiles, whose
// state is bit-identical for any number of ranks and equal to a single-process World's made from
// the same bodies in the same order with the same WorldDef (solver kJacobi): GatherStates and
// StateHash give that World's state and hash. Built only where MPI is found (CMake option
// QUADRANT_MPI, target quadrant::mpi); the engine itself never needs MPI.
//
// Decomposition (after pe / waLBerla): the scene bounds are cut into a fixed grid of tiles, dealt
// to the ranks in contiguous runs of Morton (Z) order (at 2x2 tiles and 4 ranks: the thesis's
// four quadrants). A moving body belongs to the rank whose tile holds its centre of mass; static
// bodies are known to every rank. The step's phases are described above DistributedWorld.
//
// Cost: for k velocity iterations a step takes k + 2 neighbour rounds (one message to every
// neighbour rank each, empty or not, read in rank order) and two small collectives. The Jacobi
// solve needs about four times pgs's iterations for the same hold (base-10 pyramid, 300 steps,
// apex drift: Jacobi 0.013 m at 32 iterations, pgs 0.013 m at 8; jacobi_solve.h).
//
// Solvers: only kJacobi; pgs, soft_step and the thesis solver are sequential over a global order,
// and splitting them changes their arithmetic (jacobi_solve.h). Sleep and the quadrants scheme
// are refused. Bad input throws quadrant::Error with the same message on every rank (every check
// runs on values all ranks share), so a program that lets it propagate exits non-zero on every
// rank instead of leaving the others waiting. docs/distributed.md describes use and results.
#pragma once

#include <mpi.h>

#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "quadrant/world.h"

namespace quadrant {

/// How the world is cut among ranks.
struct DistributedDef {
  AABB bounds{{-50, -50}, {50, 50}};  ///< the tiled region (m), finite, non-empty
  /// Tiles along x and y, each in [1, 1024]; the rank count must not exceed tilesX * tilesY.
  /// A tile must be at least twice as wide as the farthest any moving body's broad-phase box
  /// reaches from its centre (shape, half the speculative distance, one step's sweep): halo and
  /// migration then only involve adjacent tiles.
  int tilesX = 2;
  int tilesY = 2;
  /// Load balance: every rebalanceInterval steps (0: never, the default) the ranks' work in the
  /// last step is compared; if the most loaded rank has more than rebalanceThreshold times the
  /// mean, the tiles are dealt again by their cost (Rebalance). >= 0.
  int rebalanceInterval = 0;
  Real rebalanceThreshold = Real(1.2);  ///< max / mean work that triggers a rebalance, >= 1
};

/// What this rank did in the last Step.
struct DistributedStats {
  int ownedBodies = 0;    ///< moving bodies owned (statics are not counted)
  int shadowBodies = 0;   ///< shadows received from neighbours
  int migratedIn = 0;     ///< bodies received by migration
  int contacts = 0;       ///< contacts touching owned bodies
  int rounds = 0;         ///< neighbour rounds (one message to every neighbour each)
  int64_t bytesSent = 0;  ///< payload bytes sent to neighbours
  int neighbours = 0;
  int rebalances = 0;       ///< tile re-deals at the start of the step (0 or 1)
  /// 1 if the step kept last step's local arrays (no body left or arrived, no tile changed owner,
  /// the same shadows came): only the shadows' rows and the boxes were written; 0 if it patched
  /// (layoutPatched) or rebuilt them.
  int layoutKept = 0;
  /// 1 if the step patched last step's local arrays instead (bodies left or arrived, or other
  /// shadows came, the tiles' owners unchanged): the kept rows stayed in place and only the
  /// arrivals' and shadows' rows were written from records, into freed rows first.
  int layoutPatched = 0;
  /// Kept rows the patch moved down into freed rows (more rows were freed than filled).
  int rowsMoved = 0;
  /// Load imbalance of the step: max / mean over ranks of the work (owned bodies plus their
  /// contacts), the same on every rank.
  double imbalance = 1;
  /// Where this rank's step went (ms, wall clock), stage by stage; they add up to the step. halo:
  /// the reach reduction; migrate and shadows: those rounds with their packing; collide: the
  /// local arrays, pairs and contacts; solve: the Jacobi work; exchange: the velocity rounds
  /// between iterations with their packing; rest: the warm-start cache, the hand-back and the
  /// counts' reduction. wait: the part of all rounds spent in MPI receive and completion calls
  /// (waiting for the slowest neighbour, and the transfer), and of the halo's reduction.
  double haloMs = 0, migrateMs = 0, shadowsMs = 0, collideMs = 0, solveMs = 0, exchangeMs = 0, restMs = 0;
  double waitMs = 0;
};

/// One body's state as gathered from its owner.
struct BodyState {
  uint32_t id = 0;  ///< index of the body in the loaded scene
  Vec2 position;
  Rot rotation;
  Vec2 linearVelocity;
  Real angularVelocity = 0;
  Real mass = 0;  ///< 0 for static and kinematic bodies
};

// The step, on every rank:
//   1. migration: a body whose centre entered another rank's tile is sent there, with the
//      warm-start impulses of its contacts (bodies outside the bounds belong to the nearest
//      edge tile);
//   2. shadows: every moving body is sent, as a read-only shadow, to each other rank owning a
//      tile that its broad-phase box reaches when widened by the largest such box's reach (so a
//      rank sees every body that can touch one of its own);
//   3. each rank finds the contacts of its own bodies and runs the Jacobi solve
//      (engine/src/dynamics/jacobi_solve.h, SolverType::kJacobi): one exchange of its boundary
//      bodies' velocities and contact counts after warm starting, one after every velocity
//      iteration but the last;
//   4. the global body count and an id checksum are compared with the loaded scene's by exact
//      integer sums (nothing lost, nothing duplicated).
// A round sends exactly one message to every neighbour rank (a rank owning a tile next to one of
// its own) and reads the neighbours' messages in rank order, never arrival order. The two
// collectives are the halo reach (an allreduce) and every rank's body count, id checksum and work
// (an allgather);
// with load balancing on, every rebalanceInterval steps an allreduce of the tiles' work and, when
// it re-deals them, an all-to-all of the bodies that change owner.
// Determinism: each rank computes every contact of its own bodies, each pair oriented and the
// contacts ordered by body id, so every body sees the same contacts, in the same order, with the
// same arithmetic as in one process.
class DistributedWorld {
 public:
  /// Collective over `comm` (duplicated). Throws quadrant::Error on every rank for an invalid
  /// WorldDef or DistributedDef, a solver other than kJacobi, sleep, the quadrants scheme, or
  /// more ranks than tiles.
  DistributedWorld(const WorldDef& def, const DistributedDef& dist, MPI_Comm comm);
  ~DistributedWorld();
  DistributedWorld(const DistributedWorld&) = delete;
  DistributedWorld& operator=(const DistributedWorld&) = delete;

  /// Collective: every rank passes the whole scene; body i gets id i. Throws quadrant::Error on
  /// every rank if the scenes differ between ranks or a body is invalid (nothing is loaded then).
  void Load(std::span<const BodyDef> bodies);

  /// Collective: one step of dt (validated as World::Step). Throws quadrant::Error on every rank
  /// if a body outgrows the tiles or the body count or id checksum ever disagrees.
  void Step(Real dt);

  /// Collective: deals the tiles again by the last step's work per tile (each owned body and each
  /// of its contacts, booked to the tile its centre was in), in Morton order, contiguous runs of
  /// about equal work, and moves every body whose tile changed owner (with its warm-start
  /// entries). The states stay the same bits: the arithmetic does not depend on the partition.
  void Rebalance();
  /// The owner rank of every tile (index tx + ty * tilesX).
  std::vector<int> TileOwners() const;

  /// Collective: every body's state, in id order, on every rank.
  std::vector<BodyState> GatherStates() const;
  /// Collective: World::StateHash of the gathered states (same fields, same order).
  uint64_t StateHash() const;

  /// Collective: writes the world to `path` (rank 0 writes): every body in id order with its mass
  /// data, and the warm-start impulses of every contact, followed by a checksum. The file is for
  /// this build (it records the sizes of its records and of Real and refuses others).
  /// Throws quadrant::Error on every rank if the file cannot be written.
  void WriteCheckpoint(const std::string& path) const;
  /// Collective: replaces this world's bodies and warm-start impulses by the checkpoint's, on this
  /// world's ranks and tiles (any rank count: bodies go to the rank holding their centre). Stepping
  /// on then gives the states the written world would have had. Throws quadrant::Error on every
  /// rank, leaving the world as it was, for a missing, truncated or corrupt file.
  void ReadCheckpoint(const std::string& path);

  int Rank() const;
  int Size() const;
  const DistributedStats& GetStats() const;
  /// This rank's owned body ids (tests and drawing: bodies coloured by rank).
  std::vector<uint32_t> OwnedIds() const;

  struct Impl;

 private:
  std::unique_ptr<Impl> impl_;
};

}  // namespace quadrant
