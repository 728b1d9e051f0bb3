// The operation supervisor's cost at the edge and the verifier's time.
//
//   build/release/bin/smc-bench-grafcet
//
// * Engine/smc2/changing: evaluations per second of SMC II (cell/grafcets/
//   smc2.grafcet) on a fixed pseudo-random input sequence in which each of
//   a..e flips with probability 1/4 per evaluation (the situation changes on
//   about a third of the evaluations). Goal: >= 10 million/s on one core.
// * Baseline/smc2/changing: the same supervisor hand-written as a switch
//   statement (what the paper's "C module" is), same semantics, same
//   sequence; checked to agree with the engine before timing.
// * Engine/*/steady: inputs that do not change (the usual case at 2 kHz).
// * Verify/*: the exhaustive verifier on each supervisor; Parse/smc2.

#include <benchmark/benchmark.h>

#include <bit>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "smc/grafcet/engine.hpp"
#include "smc/grafcet/parser.hpp"
#include "smc/grafcet/verifier.hpp"

namespace {

using smc::grafcet::Engine;
using smc::grafcet::Grafcet;
using smc::grafcet::Mask;

std::string path(const char* name) {
  return std::string(SMC_SOURCE_DIR) + "/cell/grafcets/" + name;
}

Grafcet load(const char* name) {
  smc::grafcet::ParseResult r = smc::grafcet::parse_file(path(name));
  if (!r.ok()) {
    for (const auto& d : r.errors) std::fprintf(stderr, "%s\n", d.str().c_str());
    std::exit(2);
  }
  return std::move(*r.grafcet);
}

// Each input bit flips with probability 1/4 per step (xorshift, fixed seed).
const std::vector<Mask>& changing_inputs() {
  static const std::vector<Mask> seq = [] {
    std::vector<Mask> v(1 << 16);
    std::uint64_t x = 0x9E3779B97F4A7C15ull;
    Mask in = 0;
    for (Mask& m : v) {
      x ^= x << 13;
      x ^= x >> 7;
      x ^= x << 17;
      const std::uint64_t y = x * 0x2545F4914F6CDD1Dull;
      in ^= (y & (y >> 32)) & 0x1Fu;
      m = in;
    }
    return v;
  }();
  return seq;
}

// SMC II written by hand as the paper's "C module" would be, with the
// engine's semantics: transient rounds, edges in the first round only,
// checking orders (2) before (3), then (5), (7), (6).
class HandWrittenSmc2 {
 public:
  // Module bits as in smc2.grafcet's action order: A B C D E G H I J K.
  static constexpr std::uint32_t A = 1u << 0, B = 1u << 1, C = 1u << 2, D = 1u << 3, E = 1u << 4,
                                 G = 1u << 5, H = 1u << 6, I = 1u << 7, J = 1u << 8, K = 1u << 9;

  struct Out {
    std::uint32_t step;
    std::uint32_t modules;
    std::uint32_t resets;
  };

  Out update(std::uint32_t in) {
    const bool a = (in & 1u) != 0;
    const bool b = (in & 2u) != 0;
    bool rc = first_ ? false : ((in & ~prev_) & 4u) != 0;
    bool rd = first_ ? false : ((in & ~prev_) & 8u) != 0;
    bool re = first_ ? false : ((in & ~prev_) & 16u) != 0;
    std::uint32_t resets = first_ ? (E | K) : 0u;
    first_ = false;
    for (int round = 0; round < 128; ++round) {
      std::uint32_t next = step_;
      switch (step_) {
        case 1:
          next = 2;
          break;
        case 2:
          if (a)
            next = 5;
          else if (b)
            next = 3;
          break;
        case 3:
          next = 4;
          break;
        case 4:
          if (a)
            next = 5;
          else if (!b)
            next = 2;
          else if (rc || rd)
            next = 6;
          break;
        case 5:
          if (!a) next = 2;
          break;
        case 6:
          if (re) next = 2;
          break;
        default:
          break;
      }
      if (next == step_) break;
      step_ = next;
      if (step_ == 3) resets |= E | K;
      rc = rd = re = false;
    }
    prev_ = in;
    static constexpr std::uint32_t kModules[7] = {
        0, 0, A | B | I | J, 0, A | B | I | J | D | E | H | K, A | B | C, A | G};
    return {step_, kModules[step_], resets};
  }

 private:
  std::uint32_t step_ = 1;
  std::uint32_t prev_ = 0;
  bool first_ = true;
};

void check_baseline_agrees(const Grafcet& g) {
  Engine e(g);
  HandWrittenSmc2 h;
  std::size_t changes = 0;
  for (const Mask in : changing_inputs()) {
    const auto& r = e.evaluate(in);
    const auto o = h.update(static_cast<std::uint32_t>(in));
    changes += r.changed ? 1u : 0u;
    const std::uint32_t step =
        e.step_number(static_cast<std::size_t>(std::countr_zero(r.active_steps)));
    if (step != o.step || r.level_actions != o.modules || r.impulse_actions != o.resets) {
      std::fprintf(stderr, "baseline disagrees with the engine\n");
      std::exit(3);
    }
  }
  std::fprintf(stderr, "input sequence: %zu evaluations, situation changed on %zu\n",
               changing_inputs().size(), changes);
}

void BM_Engine_Changing(benchmark::State& state, const char* file) {
  const Grafcet g = load(file);
  if (std::string(file) == "smc2.grafcet") check_baseline_agrees(g);
  Engine e(g);
  const std::vector<Mask>& seq = changing_inputs();
  std::size_t i = 0;
  Mask sink = 0;
  for (auto _ : state) {
    sink ^= e.evaluate(seq[i]).level_actions;
    i = (i + 1) & (seq.size() - 1);
  }
  benchmark::DoNotOptimize(sink);
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()));
}

void BM_Baseline_Changing(benchmark::State& state) {
  HandWrittenSmc2 h;
  const std::vector<Mask>& seq = changing_inputs();
  std::size_t i = 0;
  std::uint32_t sink = 0;
  for (auto _ : state) {
    sink ^= h.update(static_cast<std::uint32_t>(seq[i])).modules;
    i = (i + 1) & (seq.size() - 1);
  }
  benchmark::DoNotOptimize(sink);
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()));
}

void BM_Engine_Steady(benchmark::State& state, const char* file) {
  const Grafcet g = load(file);
  Engine e(g);
  const Mask contact = Mask{1} << g.input_index("b");
  e.evaluate(contact);
  Mask sink = 0;
  for (auto _ : state) {
    Mask in = contact;
    benchmark::DoNotOptimize(in);
    sink ^= e.evaluate(in).level_actions;
  }
  benchmark::DoNotOptimize(sink);
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()));
}

void BM_Verify(benchmark::State& state, const char* file) {
  const Grafcet g = load(file);
  std::size_t evolutions = 0;
  for (auto _ : state) {
    const smc::grafcet::Report r = smc::grafcet::verify(g);
    if (!r.ok()) state.SkipWithError("verification failed");
    evolutions = r.evolutions;
    benchmark::DoNotOptimize(r.states);
  }
  state.counters["evolutions"] = static_cast<double>(evolutions);
}

void BM_Parse(benchmark::State& state, const char* file) {
  const Grafcet g = load(file);  // fail early if it does not parse
  (void)g;
  for (auto _ : state) {
    smc::grafcet::ParseResult r = smc::grafcet::parse_file(path(file));
    benchmark::DoNotOptimize(r.grafcet);
  }
}

}  // namespace

BENCHMARK_CAPTURE(BM_Engine_Changing, smc2, "smc2.grafcet");
BENCHMARK(BM_Baseline_Changing)->Name("BM_Baseline_Changing/smc2_hand_written_switch");
BENCHMARK_CAPTURE(BM_Engine_Changing, smc1, "smc1.grafcet");
BENCHMARK_CAPTURE(BM_Engine_Steady, smc2, "smc2.grafcet");
BENCHMARK_CAPTURE(BM_Verify, smc1, "smc1.grafcet")->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_Verify, smc2, "smc2.grafcet")->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_Parse, smc2, "smc2.grafcet")->Unit(benchmark::kMicrosecond);

BENCHMARK_MAIN();
