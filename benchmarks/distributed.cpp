// quadrant_distributed: one distributed run under mpirun, for tools/quadrant bench --ranks.
//
//   mpirun -np R quadrant_distributed --scene circle_stress|many_pyramids|pyramid --count N [--per-rank] [--steps S]
//          [--warmup W] [--tiles T] [--solver soft_step|jacobi] [--iterations K] [--threads N] [--world] [--independent]
//
// Rank 0 prints one JSON object (a run of distributed.json): ms per step (the slowest rank's wall
// time over the measured steps), neighbour rounds per step, payload bytes sent per step (all
// ranks), bytes per shadow body, shadow fraction (shadows / bodies), imbalance (max / mean over the
// ranks of owned bodies plus their contacts, averaged over the steps; a work measure, not a time),
// the state hash, and peak resident memory summed over the ranks (and per body); oversubscribed
// when ranks x threads exceed the cores. With --independent (and --per-rank), every rank steps its
// own one-rank world on the one-rank scene at the same time: the time R such processes take side
// by side, the weak-scaling ceiling of the machine itself (shared caches, memory, clocks), with no
// rank waiting for another. With --world,
// also world_ms_per_step: the single-process World with its default engine (the quadrant adapter's
// mapping of the scene, --threads threads) on the same bodies, timed the same way on rank 0 after
// the distributed run. For the pyramid, apex_drift_m: how far its apex moved from its pose after
// the warm-up (the largest of samples every 30 steps).
// Bad options: one line on stderr, exit 2 (every rank parses the same arguments).
#include <mpi.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <thread>
#include <vector>

#include "cli_args.h"
#include "quadrant/distributed_world.h"
#include "quadrant/error.h"
#include "quadrant/world.h"
#include "quadrant_variant.h"
#include "scenes.h"

using namespace quadrant;

namespace {

// The scene's bodies through the scene API's own mapping (scene::ToBodyDef).
std::vector<BodyDef> ToBodyDefs(const scene::Scene& s) {
  std::vector<BodyDef> out;
  out.reserve(s.bodies.size());
  for (const scene::BodyDesc& b : s.bodies) out.push_back(scene::ToBodyDef(b));
  return out;
}

// Peak resident memory of this process (kB, Linux VmHWM), 0 where unknown.
long PeakRssKb() {
  std::FILE* f = std::fopen("/proc/self/status", "r");
  if (f == nullptr) return 0;
  char line[256];
  long kb = 0;
  while (std::fgets(line, sizeof line, f) != nullptr) {
    if (std::strncmp(line, "VmHWM:", 6) == 0) kb = std::strtol(line + 6, nullptr, 10);
  }
  std::fclose(f);
  return kb;
}

}  // namespace

int main(int argc, char** argv) {
  MPI_Init(&argc, &argv);
  int rank = 0, size = 1;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  std::string sceneName = "circle_stress";
  int count = 16000, steps = 100, warmup = 10, tiles = 0, iterations = 8, threads = 1;
  bool perRank = false, compareWorld = false, independent = false;
  std::string solverName = "soft_step";  // the engine's default (WorldDef::solver)
  std::string ownersPath;  // --owners FILE: every body's position, radius and owner rank as CSV
  cli::Parser parser("quadrant_distributed",
                "One distributed run under mpirun (tools/quadrant bench --ranks): rank 0 prints one JSON "
                "object\n(ms per step, neighbour rounds, payload bytes, shadow fraction, imbalance, state "
                "hash, peak memory).");
  parser.Name("--scene", &sceneName, {"circle_stress", "pyramid", "many_pyramids"}, "scene", "the scene");
  parser.Int("--count", &count, 1, 10000000,
             "bodies (circle_stress), boxes (many_pyramids: base-10 pyramids in rows on shelves, at least 55), "
             "or the pyramid's base when below 200 (else 20)");
  parser.Flag("--per-rank", &perRank, "--count is per rank (circle_stress, many_pyramids)");
  parser.Int("--steps", &steps, 1, 1000000, "measured steps");
  parser.Int("--warmup", &warmup, 0, 1000000, "steps before measuring");
  parser.Int("--tiles", &tiles, 1, 1024, "tiles per side")
      .Default("about 14 m per tile (circle_stress), 11 m across (many_pyramids), 2 (pyramid)");
  parser.Name("--solver", &solverName, {"soft_step", "jacobi"}, "solver",
              "jacobi: the same bits on any rank count (--iterations); soft_step: the World's default engine inside each "
              "rank (its default budget)");
  parser.Int("--iterations", &iterations, 1, 1000, "velocity iterations (jacobi)");
  parser.Int("--threads", &threads, 1, 64, "threads inside each rank (WorldDef::threadCount; also the World's with --world)");
  parser.Flag("--independent", &independent,
              "with --per-rank: each rank steps its own one-rank world (MPI_COMM_SELF) at the same time; the "
              "machine's ceiling for weak scaling (no rank waits for another)");
  parser.Flag("--world", &compareWorld, "also time the World's default engine on the same scene (world_ms_per_step)");
  parser.String("--owners", &ownersPath, "FILE", "write every body's position, radius and owner rank as CSV");
  parser.Quiet(rank != 0);  // every rank parses the same arguments; rank 0 speaks for them
  parser.OnExit([](int status) {
    MPI_Finalize();
    std::exit(status);
  });
  parser.Parse(argc, argv);
  int code = 0;
  if (independent && (!perRank || compareWorld || !ownersPath.empty() || sceneName == "pyramid")) {
    if (rank == 0) {
      std::fprintf(stderr, "quadrant_distributed: --independent needs --per-rank (circle_stress, many_pyramids), without --world or --owners\n");
    }
    MPI_Finalize();
    return 2;
  }
  // The ranks the scene is sized for and split over: one each with --independent.
  const int worldRanks = independent ? 1 : size;
  MPI_Comm worldComm = independent ? MPI_COMM_SELF : MPI_COMM_WORLD;
  try {
    scene::Scene s;
    DistributedDef dist;
    if (sceneName == "circle_stress") {
      scene::StressParams p;
      p.count = perRank ? count * worldRanks : count;
      s = scene::MakeStressScene(p);
      dist.bounds = s.bounds;
      // Tiles of about 14 m (a circle reaches 0.51 m from its centre): at 64000 bodies 32 x 32.
      if (tiles == 0) tiles = std::clamp(int((s.bounds.upper.x - s.bounds.lower.x) / 14), 2, 64);
    } else if (sceneName == "many_pyramids") {
      // The dense scene for weak scaling: Box2D 3's many_pyramids (base-10 pyramids on shelves),
      // `count` boxes (per rank with --per-rank). Tiles about a pyramid's cell (11 m) across.
      s = scene::MakeManyPyramids(perRank ? count * worldRanks : count);
      dist.bounds = s.bounds;
      if (tiles == 0) tiles = std::clamp(int((s.bounds.upper.x - s.bounds.lower.x) / 11), 2, 64);
    } else {
      // The pyramid of the hard cases with `count` as its base (default 20 when --count is not
      // below 200), centred on the corner of four tiles.
      const int base = count >= 200 ? 20 : count;
      s = scene::MakePyramid(base);
      Real lo = 1e9, hi = -1e9, top = -1e9, bottom = 1e9;
      for (const scene::BodyDesc& b : s.bodies) {
        if (!b.dynamic) continue;
        lo = std::min(lo, b.position.x), hi = std::max(hi, b.position.x);
        top = std::max(top, b.position.y), bottom = std::min(bottom, b.position.y);
      }
      const Vec2 mid{(lo + hi) / 2, (bottom + top) / 2};
      const Real half = std::max(Real(20), (hi - lo));
      dist.bounds = AABB{mid - Vec2{half, half}, mid + Vec2{half, half}};
      if (tiles == 0) tiles = 2;
    }
    dist.tilesX = dist.tilesY = tiles;
    WorldDef def;
    if (solverName == "soft_step") {
      def = scene::QuadrantVariant{}.MakeWorldDef(s, threads);  // what --world times
      def.effects.sleep = false;
    } else {
      def.gravity = s.gravity;
      def.solver = SolverType::kJacobi;
      def.velocityIterations = iterations;
      def.threadCount = threads;
      def.restitutionThreshold = s.restitutionThreshold;
      def.effects = s.effects;
    }
    const std::vector<BodyDef> bodies = ToBodyDefs(s);
    DistributedWorld dw(def, dist, worldComm);
    dw.Load(bodies);
    for (int i = 0; i < warmup; ++i) dw.Step(s.timeStep);
    // The pyramid's stability (the hard cases' measure, from the pose after the warm-up, which
    // settles it): the farthest its apex, the highest box at the start, moves from there.
    size_t apex = 0;
    for (size_t i = 0; i < bodies.size(); ++i) {
      if (bodies[i].type == BodyType::kDynamic && bodies[i].position.y > bodies[apex].position.y) apex = i;
    }
    const bool pyramid = sceneName == "pyramid";
    const Vec2 apexFrom = pyramid ? dw.GatherStates()[apex].position : Vec2{};
    double bytes = 0, shadows = 0, imbalance = 0;
    int rounds = 0;
    // Per stage, this rank's ms summed over the timed steps (DistributedStats).
    constexpr int kStages = 8;
    const char* stageNames[kStages] = {"halo", "migrate", "shadows", "collide", "solve", "exchange", "rest", "wait"};
    double stageMs[kStages] = {};
    MPI_Barrier(MPI_COMM_WORLD);
    const double t0 = MPI_Wtime();
    double apexDrift = -1, sampleSeconds = 0;  // the largest apex drift of the samples, and their time
    for (int i = 0; i < steps; ++i) {
      dw.Step(s.timeStep);
      // The hard cases sample every 0.5 s (30 steps at 60 Hz) and after the last step; the
      // samples' time is taken out of the timing.
      if (pyramid && ((i + 1) % 30 == 0 || i + 1 == steps)) {
        const double from = MPI_Wtime();
        apexDrift = std::max(apexDrift, double(Length(dw.GatherStates()[apex].position - apexFrom)));
        sampleSeconds += MPI_Wtime() - from;
      }
      const DistributedStats& st = dw.GetStats();
      // This rank's sums, added over the ranks after the timed steps: the loop meets the other
      // ranks only inside Step, as a user's loop does.
      bytes += double(st.bytesSent);
      shadows += double(st.shadowBodies);
      imbalance += st.imbalance;  // the same on every rank
      rounds = st.rounds;
      const double stage[kStages] = {st.haloMs, st.migrateMs, st.shadowsMs, st.collideMs, st.solveMs, st.exchangeMs, st.restMs, st.waitMs};
      for (int k = 0; k < kStages; ++k) stageMs[k] += stage[k];
    }
    const double mine = MPI_Wtime() - t0 - sampleSeconds;
    double slowest = 0;
    MPI_Allreduce(&mine, &slowest, 1, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD);
    {
      double mineSums[2] = {bytes, shadows}, sums[2];
      MPI_Allreduce(mineSums, sums, 2, MPI_DOUBLE, MPI_SUM, MPI_COMM_WORLD);
      bytes = sums[0];
      shadows = sums[1];
    }
    // The profile of the slowest rank (the one whose step time the run reports) and the mean.
    double stageMax[kStages], stageSum[kStages];
    MPI_Allreduce(stageMs, stageMax, kStages, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD);
    MPI_Allreduce(stageMs, stageSum, kStages, MPI_DOUBLE, MPI_SUM, MPI_COMM_WORLD);
    std::string profile;
    for (int k = 0; k < kStages; ++k) {
      char cell[96];
      std::snprintf(cell, sizeof cell, "%s\"%s\": [%.4f, %.4f]", k ? ", " : "", stageNames[k], stageSum[k] / size / steps,
                    stageMax[k] / steps);
      profile += cell;
    }
    const uint64_t hash = dw.StateHash();
    // Memory: peak resident size summed over the ranks (each rank also holds the whole scene's
    // BodyDefs, as Load takes them, and the MPI library's buffers).
    const long rssKb = PeakRssKb();
    long rssTotalKb = 0;
    MPI_Allreduce(&rssKb, &rssTotalKb, 1, MPI_LONG, MPI_SUM, MPI_COMM_WORLD);
    if (!ownersPath.empty()) {
      // The thesis's Figure 13 by rank (tools/figure13_ranks.py): owners gathered to rank 0.
      const std::vector<BodyState> states = dw.GatherStates();
      const std::vector<uint32_t> mine = dw.OwnedIds();
      const int n = static_cast<int>(mine.size());
      std::vector<int> counts(static_cast<size_t>(size)), displs(static_cast<size_t>(size));
      MPI_Gather(&n, 1, MPI_INT, counts.data(), 1, MPI_INT, 0, MPI_COMM_WORLD);
      int total = 0;
      for (int r = 0; r < size; ++r) displs[size_t(r)] = total, total += counts[size_t(r)];
      std::vector<uint32_t> ids(size_t(std::max(total, 1)));
      MPI_Gatherv(mine.data(), n, MPI_UINT32_T, ids.data(), counts.data(), displs.data(), MPI_UINT32_T, 0, MPI_COMM_WORLD);
      if (rank == 0) {
        std::vector<int> owner(bodies.size(), -1);  // -1: static (on every rank)
        for (int r = 0; r < size; ++r) {
          for (int k = 0; k < counts[size_t(r)]; ++k) owner[ids[size_t(displs[size_t(r)] + k)]] = r;
        }
        std::FILE* f = std::fopen(ownersPath.c_str(), "w");
        if (f == nullptr) throw Error("cannot write '" + ownersPath + "'");
        const std::vector<int> tileOwners = dw.TileOwners();
        std::fprintf(f, "# bounds %g %g %g %g tiles %d %d ranks %d steps %d owners", double(dist.bounds.lower.x),
                     double(dist.bounds.lower.y), double(dist.bounds.upper.x), double(dist.bounds.upper.y), dist.tilesX,
                     dist.tilesY, size, warmup + steps);
        for (int o : tileOwners) std::fprintf(f, " %d", o);
        std::fprintf(f, "\nx,y,radius,rank\n");
        for (const BodyState& b : states) {
          if (owner[b.id] < 0 || bodies[b.id].shape.type != ShapeType::kCircle) continue;
          std::fprintf(f, "%.4f,%.4f,%.4f,%d\n", double(b.position.x), double(b.position.y),
                       double(bodies[b.id].shape.circle.radius), owner[b.id]);
        }
        std::fclose(f);
      }
    }
    // After the distributed run: timed first, the World shared the core with mpirun's daemon
    // starting up (1.05-1.80 ms a step where quadrant_bench measured 0.83-1.32 minutes apart).
    double worldMs = 0;
    if (compareWorld && rank == 0) {
      World world(scene::QuadrantVariant{}.MakeWorldDef(s, threads));
      for (const BodyDef& b : bodies) world.CreateBody(b);
      for (int i = 0; i < warmup; ++i) world.Step(s.timeStep);
      const double w0 = MPI_Wtime();
      for (int i = 0; i < steps; ++i) world.Step(s.timeStep);
      worldMs = 1000.0 * (MPI_Wtime() - w0) / steps;
    }
    if (rank == 0) {
      char world[128] = "";
      if (compareWorld) std::snprintf(world, sizeof world, ", \"world_ms_per_step\": %.4f", worldMs);
      if (apexDrift >= 0) {
        const size_t used = std::strlen(world);
        std::snprintf(world + used, sizeof world - used, ", \"apex_drift_m\": %.5f", apexDrift);
      }
      const unsigned cores = std::max(1u, std::thread::hardware_concurrency());
      // Bodies stepped in all (the independent worlds' together).
      const double allBodies = double(bodies.size()) * (independent ? size : 1);
      std::printf(
          "{\"scene\": \"%s\", \"solver\": \"%s\", \"ranks\": %d, \"bodies\": %.0f, \"steps\": %d, \"warmup\": %d, \"tiles\": %d, "
          "\"iterations\": %d, \"threads\": %d, \"weak\": %s, \"independent\": %s, \"ms_per_step\": %.4f, \"rounds_per_step\": %d, \"bytes_per_step\": %.1f, "
          "\"bytes_per_boundary_body\": %.1f, \"shadow_fraction\": %.5f, \"imbalance\": %.4f, "
          "\"state_hash\": \"%016llx\", \"oversubscribed\": %s, \"cores\": %u, \"peak_rss_mb\": %.1f, "
          "\"rss_bytes_per_body\": %.0f, \"stage_ms\": {%s}%s}\n",
          sceneName.c_str(), solverName.c_str(), size, allBodies, steps, warmup, tiles, iterations, threads, perRank ? "true" : "false",
          independent ? "true" : "false",
          1000.0 * slowest / steps, rounds, bytes / steps, shadows > 0 ? bytes / shadows : 0.0,
          shadows / steps / allBodies, imbalance / steps, (unsigned long long)hash,
          unsigned(size * threads) > cores ? "true" : "false", cores, rssTotalKb / 1024.0,
          1024.0 * double(rssTotalKb) / allBodies, profile.c_str(), world);
    }
  } catch (const Error& e) {
    std::fprintf(stderr, "quadrant_distributed: rank %d: error: %s\n", rank, e.what());
    code = 1;
  }
  MPI_Finalize();
  return code;
}
