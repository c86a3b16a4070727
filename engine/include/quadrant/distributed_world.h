// Quadrant over MPI: a world split among processes (ranks) by fixed world-space tiles. Built only
// where MPI is found (CMake option QUADRANT_MPI, target quadrant::mpi); the engine itself never
// needs MPI.
//
// Decomposition (after pe / waLBerla): the scene bounds are cut into a fixed grid of tiles, dealt
// to the ranks in contiguous runs of equal numbers of bodies (Load, ReadCheckpoint; Rebalance
// by work) along a bisection order (the longer side cut, recursively, where the tiles' bodies
// split evenly: with bodies spread evenly, Morton (Z) order on a power-of-two square grid; at
// 2x2 tiles and 4 ranks the thesis's four quadrants; at 2 ranks two halves). A moving body belongs to the rank whose tile holds its centre of mass; static
// bodies are known to every rank. The step's phases are described above DistributedWorld.
//
// Solvers (WorldDef::solver):
// - kSoftStep, the default: the World's soft step on each rank's bodies and the shadows of its
//   neighbours' (Gauss-Seidel inside a rank), the boundary bodies' solver states sent by their
//   owners before each sub-step's solve pass, before its positions move and at the end (Jacobi
//   across the boundary, as pe's subdomain Gauss-Seidel). On one rank its state is the World's
//   bit for bit; on more it depends on the rank count (each rank solves its boundary contacts
//   from its own side), the same on any thread count and every run. Cost: 2n + 1 neighbour
//   rounds for n sub-steps, plus 2. Measured (amd-epyc-2c; docs/distributed.md): one rank
//   1.1-1.2x the World's step on circle stress and many_pyramids (medians); weak scaling to 2
//   ranks 91-95 % on many_pyramids, 85-90 % on circle stress; the base-20 pyramid across four
//   tiles holds its apex within 0.004 m over 60 s at the default 4 sub-steps on 1-4 ranks.
// - kJacobi, the deterministic option: the state is bit-identical for any number of ranks and
//   equal to a single-process World's with the same bodies and WorldDef (GatherStates and
//   StateHash give that World's state and hash). k velocity iterations take k + 2 rounds. Its
//   cost is stability: the Jacobi solve needs about four times pgs's iterations for the same
//   hold (base-10 pyramid, 300 steps, apex drift: 0.013 m at 32 iterations, pgs 0.013 m at 8;
//   jacobi_solve.h), and at 32 iterations one rank is 10-13x the World on the base-20 pyramid.
// pgs and the thesis solver are refused. Sleep and the quadrants scheme are refused. Bad input
// throws quadrant::Error with the same message on every rank (every check runs on values all
// ranks share), so a program that lets it propagate exits non-zero on every rank instead of
// leaving the others waiting. docs/distributed.md describes use and results.
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
  /// local arrays, pairs and contacts; solve: the solver's work; exchange: the rounds inside the
  /// solve (kSoftStep: the solver states between passes; kJacobi: the velocities between
  /// iterations) with their packing; rest: the warm-start cache, the hand-back and the
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
//   3. each rank finds the contacts of its own bodies and solves them: kSoftStep, the soft step
//      with three exchanges of the boundary bodies' solver states per sub-step (the last
//      sub-step's third only; one more before Box2D-style bounces; only the velocities travel
//      unless the bounces moved bodies, as both sides integrate the same motion from them); kJacobi, the Jacobi solve
//      (engine/src/dynamics/jacobi_solve.h): one exchange of the boundary bodies' velocities
//      and contact counts after warm starting, one after every velocity iteration but the last;
//   4. the global body count and an id checksum are compared with the loaded scene's by exact
//      integer sums (nothing lost, nothing duplicated).
// A round sends exactly one message to every neighbour rank (a rank owning a tile next to one of
// its own) and reads the neighbours' messages in rank order, never arrival order. The two
// collectives are the halo reach (an allreduce) and every rank's body count, id checksum and work
// (an allgather);
// with load balancing on, every rebalanceInterval steps an allreduce of the tiles' work and, when
// it re-deals them, an all-to-all of the bodies that change owner.
// Determinism: each rank computes every contact of its own bodies, each pair oriented and the
// contacts ordered by body id, so every body sees the same contacts, in the same order; with
// kJacobi also the same arithmetic as in one process.
class DistributedWorld {
 public:
  /// Collective over `comm` (duplicated). Throws quadrant::Error on every rank for an invalid
  /// WorldDef or DistributedDef, a solver other than kSoftStep or kJacobi, sleep, the quadrants
  /// scheme, or more ranks than tiles.
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
  /// of its contacts, booked to the tile its centre was in), in bisection order, contiguous runs of
  /// about equal work, and moves every body whose tile changed owner (with its warm-start
  /// entries). With kJacobi the states stay the same bits: the arithmetic does not depend on the
  /// partition (with kSoftStep it does).
  void Rebalance();
  /// The owner rank of every tile (index tx + ty * tilesX).
  std::vector<int> TileOwners() const;

  /// Collective: every body's state, in id order, on every rank.
  std::vector<BodyState> GatherStates() const;
  /// Collective: World::StateHash of the gathered states (same fields, same order). With kJacobi
  /// the same for any rank count; with kSoftStep the same for any thread count on a rank count.
  uint64_t StateHash() const;

  /// Collective: writes the world to `path` (rank 0 writes): every body in id order with its mass
  /// data, and the warm-start impulses of every contact, followed by a checksum. The file is for
  /// this build (it records the sizes of its records and of Real and refuses others).
  /// Throws quadrant::Error on every rank if the file cannot be written.
  void WriteCheckpoint(const std::string& path) const;
  /// Collective: replaces this world's bodies and warm-start impulses by the checkpoint's, on this
  /// world's ranks and tiles (any rank count: bodies go to the rank holding their centre). Stepping
  /// on then gives the states the written world would have had (kJacobi; kSoftStep continues from
  /// the same bodies and impulses without that promise: the manifolds it recycles from last step
  /// are not in the file). Throws quadrant::Error on every
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
