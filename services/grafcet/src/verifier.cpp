// Exhaustive verification: breadth-first exploration of every situation
// reachable from the initial one under every valuation of the inputs the
// Grafcet reads, evolved by the same code as the Engine (net.hpp).

#include "smc/grafcet/verifier.hpp"

#include <algorithm>
#include <bit>
#include <limits>
#include <map>
#include <set>
#include <tuple>
#include <unordered_map>

#include "net.hpp"

namespace smc::grafcet {

const char* check_name(Check check) noexcept {
  switch (check) {
    case Check::kUnreachableStep:
      return "unreachable step";
    case Check::kConflict:
      return "conflict";
    case Check::kDeadlock:
      return "deadlock";
    case Check::kTransientCycle:
      return "transient cycle";
    case Check::kRoundBound:
      return "transient too long";
    case Check::kInvariant:
      return "invariant";
    case Check::kLimit:
      return "limit";
  }
  return "?";
}

namespace {

constexpr std::size_t kNone = std::numeric_limits<std::size_t>::max();

struct State {
  Mask steps = 0;
  Mask previous = 0;  // previous inputs, edge-read bits only
  std::size_t parent = kNone;
  Mask via = 0;       // inputs of the evaluation that reached it
  Mask impulses = 0;  // impulse actions fired by that evaluation
  bool leaves = false;
};

struct KeyHash {
  std::size_t operator()(const std::pair<Mask, Mask>& k) const noexcept {
    const std::uint64_t h = k.first * 0x9E3779B97F4A7C15ull ^ (k.second + 0x632BE59BD9B4E019ull);
    return static_cast<std::size_t>(h ^ (h >> 29));
  }
};

std::string steps_text(const Grafcet& g, Mask steps) {
  if (steps == 0) return "no active step";
  std::string s;
  for (Mask m = steps; m != 0; m &= m - 1) {
    if (!s.empty()) s += ' ';
    s += 'X';
    s += std::to_string(g.steps()[static_cast<std::size_t>(std::countr_zero(m))].number);
  }
  return s;
}

std::string transition_text(const Grafcet& g, std::size_t t) {
  return std::string("(").append(std::to_string(g.transitions()[t].number)).append(")");
}

class Explorer {
 public:
  Explorer(const Grafcet& g, const VerifyOptions& o) : g_(g), o_(o), net_(g) {}

  Report run() {
    read_inputs();
    r_.max_rounds = o_.max_rounds;
    for (const Invariant& inv : g_.invariants())
      r_.invariants.push_back({inv.name, inv.where, true, 0});
    if (static_cast<std::size_t>(std::popcount(r_.inputs_read)) > o_.max_inputs) {
      add({Check::kLimit,
           "inputs",
           std::to_string(std::popcount(r_.inputs_read)) +
               " inputs are read; exhaustive exploration is limited to " +
               std::to_string(o_.max_inputs),
           {},
           {}});
      return std::move(r_);
    }
    Mask v = 0;
    do {
      valuations_.push_back(v);
      v = (v - r_.inputs_read) & r_.inputs_read;
    } while (v != 0);
    r_.valuations = valuations_.size();
    fired_.assign(g_.transitions().size() + 1, 0);
    fired_ever_.assign(g_.transitions().size(), 0);
    started_ = std::chrono::steady_clock::now();
    explore();
    r_.states = states_.size();
    if (!r_.complete) return std::move(r_);  // what was not explored proves nothing
    unreachable();
    deadlocks();
    notes();
    r_.states = states_.size();
    return std::move(r_);
  }

 private:
  void read_inputs() {
    auto use = [&](const Expression& e) {
      r_.inputs_read |= e.reads[0] | e.reads[1] | e.reads[2];
      edge_inputs_ |= e.reads[1] | e.reads[2];
    };
    for (const Transition& t : g_.transitions()) use(t.receptivity);
    for (const Invariant& inv : g_.invariants()) {
      use(inv.condition);
      if (inv.next) use(*inv.next);
    }
  }

  void add(Violation v) {
    std::size_t& n = per_check_[v.check];
    if (n >= o_.max_per_check) {
      ++r_.violations_dropped;
      return;
    }
    ++n;
    r_.violations.push_back(std::move(v));
  }

  std::vector<PathStep> path_to(std::size_t index) const {
    std::vector<PathStep> path;
    for (std::size_t i = index; i != 0 && i != kNone; i = states_[i].parent)
      path.push_back({states_[i].via, states_[i].steps, states_[i].impulses, true});
    std::reverse(path.begin(), path.end());
    return path;
  }

  struct PendingConflict {
    std::size_t step;
    std::size_t first;
    std::size_t second;
    Mask situation;
  };

  void explore() {
    states_.push_back({net_.initial, 0, kNone, 0, 0, false});  // the root: before reset's
                                                               // first evaluation
    const std::uint32_t bound = std::max<std::uint32_t>(o_.max_rounds, 1u << 16);
    std::vector<Mask> seen;
    std::vector<PendingConflict> conflicts;
    for (std::size_t si = 0; si < states_.size(); ++si) {
      const State s = states_[si];
      const bool root = si == 0;
      const Mask level_before = net_.level_actions(s.steps);
      r_.reachable_steps |= s.steps;
      for (const Mask v : valuations_) {
        if (over_budget()) return;
        ++r_.evolutions;
        const Mask rise = root ? 0 : v & ~s.previous & edge_inputs_;
        const Mask fall = root ? 0 : s.previous & ~v & edge_inputs_;
        seen.clear();
        conflicts.clear();
        std::size_t round = 0;
        std::size_t cycle_from = kNone;
        auto on_round = [&](Mask before, Mask after, const std::uint32_t* fired,
                            std::uint32_t count) {
          r_.reachable_steps |= before | after;
          observe_conflicts(before, fired, count, conflicts);
          if (round++ > 0) {
            const auto it = std::find(seen.begin(), seen.end(), before);
            if (it != seen.end()) {
              cycle_from = static_cast<std::size_t>(it - seen.begin());
              return false;
            }
            seen.push_back(before);
          }
          return true;
        };
        const detail::EvolveResult e =
            detail::evolve(net_, s.steps, v, rise, fall, bound, fired_.data(), on_round);
        r_.work += std::max<std::uint64_t>(1, e.rounds);
        const Mask activated = e.activated | (root ? net_.initial : 0);
        const PathStep last{v, e.active, net_.impulse_actions(activated),
                            !e.aborted && !e.unstable};
        for (const PendingConflict& c : conflicts) report_conflict(c, si, last);
        if (e.aborted) {
          states_[si].leaves = true;
          report_cycle(
              std::vector<Mask>(seen.begin() + static_cast<std::ptrdiff_t>(cycle_from), seen.end()),
              si, last);
          continue;
        }
        if (e.unstable || e.rounds > o_.max_rounds) {
          report_long(si, last, e.unstable ? bound : e.rounds);
          if (e.unstable) continue;
        }
        r_.longest_transient = std::max(r_.longest_transient, e.rounds);
        if (e.active != s.steps) states_[si].leaves = true;
        check_invariants(si, s, level_before, rise, fall, last);
        const std::pair<Mask, Mask> key{e.active, v & edge_inputs_};
        if (index_.count(key) == 0) {
          if (states_.size() >= o_.max_states) {
            if (!state_limit_reported_)
              add({Check::kLimit,
                   "states",
                   "more than " + std::to_string(o_.max_states) +
                       " states; the exploration is incomplete",
                   {},
                   {}});
            state_limit_reported_ = true;
            continue;
          }
          index_.emplace(key, states_.size());
          states_.push_back({e.active, v & edge_inputs_, si, v, last.impulses, false});
        }
      }
    }
  }

  // Reports (once) and ends the exploration when the work or time budget is spent.
  bool over_budget() {
    const bool work = o_.max_work > 0 && r_.work >= o_.max_work;
    const bool time = o_.max_time.count() > 0 && (r_.evolutions & 255u) == 0 &&
                      std::chrono::steady_clock::now() - started_ > o_.max_time;
    if (!work && !time) return false;
    r_.complete = false;
    add({Check::kLimit,
         "budget",
         work ? "the verification budget of " + std::to_string(o_.max_work) +
                    " evolution rounds is spent after " + std::to_string(states_.size()) +
                    " states; the Grafcet is too large to verify exhaustively"
              : "the verification time budget of " + std::to_string(o_.max_time.count()) +
                    " ms is spent after " + std::to_string(states_.size()) +
                    " states; the Grafcet is too large to verify exhaustively",
         {},
         {}});
    return true;
  }

  void observe_conflicts(Mask before, const std::uint32_t* fired, std::uint32_t count,
                         std::vector<PendingConflict>& out) {
    const auto ts = g_.transitions();
    for (std::uint32_t j = 0; j < count; ++j) fired_ever_[fired[j]] = 1;
    for (std::uint32_t j = 0; j < count; ++j)
      for (std::uint32_t k = j + 1; k < count; ++k) {
        const std::size_t t = std::min(fired[j], fired[k]);
        const std::size_t u = std::max(fired[j], fired[k]);
        const Mask shared = ts[t].preceding & ts[u].preceding;
        if (shared == 0) continue;
        out.push_back({static_cast<std::size_t>(std::countr_zero(shared)), t, u, before});
      }
  }

  void report_conflict(const PendingConflict& c, std::size_t si, const PathStep& last) {
    if (!conflicts_seen_.insert({c.step, c.first, c.second}).second) return;
    const std::string step = std::to_string(g_.steps()[c.step].number);
    Violation v;
    v.check = Check::kConflict;
    v.subject = "step " + step + ": transitions " + transition_text(g_, c.first) + " and " +
                transition_text(g_, c.second);
    v.detail = "both fire from situation " + steps_text(g_, c.situation) +
               " on the last inputs below; no checking order decides between them (add "
               "'order " +
               step + ": ...')";
    v.where = g_.transitions()[c.second].where;
    v.path = path_to(si);
    v.path.push_back(last);
    add(std::move(v));
  }

  void report_cycle(std::vector<Mask> cycle, std::size_t si, const PathStep& last) {
    std::string text;
    for (Mask m : cycle) text += (text.empty() ? "" : " -> ") + steps_text(g_, m);
    text += " -> " + steps_text(g_, cycle.front());
    std::sort(cycle.begin(), cycle.end());
    if (!cycles_seen_.insert(cycle).second) return;
    Violation v;
    v.check = Check::kTransientCycle;
    v.subject = text;
    v.detail =
        "transient evolution that never reaches a stable situation; the engine "
        "would stop after " +
        std::to_string(o_.max_rounds) + " rounds and report it unstable";
    v.path = path_to(si);
    v.path.push_back(last);
    add(std::move(v));
  }

  void report_long(std::size_t si, const PathStep& last, std::uint32_t rounds) {
    if (long_reported_) return;
    long_reported_ = true;
    Violation v;
    v.check = Check::kRoundBound;
    v.subject = "transient evolution";
    v.detail = "an evaluation needs " + std::to_string(rounds) +
               " rounds of transient evolution; the engine stops after " +
               std::to_string(o_.max_rounds) + " and reports it unstable";
    v.path = path_to(si);
    v.path.push_back(last);
    add(std::move(v));
  }

  void check_invariants(std::size_t si, const State& s, Mask level_before, Mask rise, Mask fall,
                        const PathStep& last) {
    const auto invs = g_.invariants();
    if (invs.empty()) return;
    const Context before{last.inputs, rise, fall, s.steps, level_before, 0};
    const Context after{last.inputs,  rise, fall, last.steps, net_.level_actions(last.steps),
                        last.impulses};
    for (std::size_t k = 0; k < invs.size(); ++k) {
      const Invariant& inv = invs[k];
      InvariantResult& res = r_.invariants[k];
      ++res.evaluations;
      bool ok = true;
      if (inv.next)
        ok = !evaluate(inv.condition, before) || evaluate(*inv.next, after);
      else
        ok = evaluate(inv.condition, after);
      if (ok || !res.held) continue;
      res.held = false;
      Violation v;
      v.check = Check::kInvariant;
      v.subject = "invariant \"" + inv.name + "\"";
      if (inv.next)
        v.detail = "'" + inv.condition.text + "' held in " + steps_text(g_, s.steps) +
                   " with the new inputs, but '" + inv.next->text + "' is false in " +
                   steps_text(g_, last.steps) + ", the next stable situation";
      else
        v.detail = "'" + inv.condition.text + "' is false in " + steps_text(g_, last.steps);
      v.where = inv.where;
      v.path = path_to(si);
      v.path.push_back(last);
      add(std::move(v));
    }
  }

  void unreachable() {
    const auto steps = g_.steps();
    for (std::size_t i = 0; i < steps.size(); ++i) {
      if ((r_.reachable_steps >> i & 1u) != 0) continue;
      add({Check::kUnreachableStep,
           "step " + std::to_string(steps[i].number),
           "never active, not even transiently, from the initial situation",
           steps[i].where,
           {}});
    }
  }

  void deadlocks() {
    std::map<Mask, std::pair<bool, std::size_t>> groups;  // leaves, first state
    std::set<Mask> stable;
    for (std::size_t i = 0; i < states_.size(); ++i) {
      auto [it, inserted] = groups.try_emplace(states_[i].steps, states_[i].leaves, i);
      if (!inserted) it->second.first = it->second.first || states_[i].leaves;
      if (i != 0) stable.insert(states_[i].steps);
    }
    r_.stable_situations = stable.size();
    std::vector<std::pair<std::size_t, Mask>> dead;
    for (const auto& [steps, g] : groups)
      if (!g.first) dead.push_back({g.second, steps});
    std::sort(dead.begin(), dead.end());
    for (const auto& [first, steps] : dead) {
      Violation v;
      v.check = Check::kDeadlock;
      v.subject = "situation " + steps_text(g_, steps);
      v.detail = "no input valuation leads out of it";
      if (steps != 0) {
        const auto i = static_cast<std::size_t>(std::countr_zero(steps));
        v.where = g_.steps()[i].where;
      }
      v.path = path_to(first);
      add(std::move(v));
    }
  }

  void notes() {
    const auto ts = g_.transitions();
    for (std::size_t t = 0; t < ts.size(); ++t)
      if (fired_ever_[t] == 0)
        r_.notes.push_back("transition " + transition_text(g_, t) + " never fires");
    std::string unused;
    const auto inputs = g_.inputs();
    for (std::size_t i = 0; i < inputs.size(); ++i)
      if ((r_.inputs_read >> i & 1u) == 0) unused += (unused.empty() ? "" : ", ") + inputs[i].name;
    if (!unused.empty()) r_.notes.push_back("inputs declared but never read: " + unused);
  }

  const Grafcet& g_;
  const VerifyOptions& o_;
  detail::Net net_;
  Report r_;
  Mask edge_inputs_ = 0;
  std::vector<Mask> valuations_;
  std::vector<State> states_;
  std::unordered_map<std::pair<Mask, Mask>, std::size_t, KeyHash> index_;
  std::vector<std::uint32_t> fired_;
  std::vector<std::uint8_t> fired_ever_;
  std::map<Check, std::size_t> per_check_;
  std::set<std::tuple<std::size_t, std::size_t, std::size_t>> conflicts_seen_;
  std::set<std::vector<Mask>> cycles_seen_;
  bool long_reported_ = false;
  bool state_limit_reported_ = false;
  std::chrono::steady_clock::time_point started_{};
};

}  // namespace

Report verify(const Grafcet& grafcet, const VerifyOptions& options) {
  return Explorer(grafcet, options).run();
}

}  // namespace smc::grafcet
