// The stepping simulator: contact along the part, feed hold, determinism,
// status flags, real-time safety (no allocation in step()), and agreement
// with the batch runs.

#include "smc/machining/simulator.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <vector>

#include "alloc_counter.hpp"
#include "smc/machining/paper_case.hpp"
#include "smc/machining/tds.hpp"

namespace mc = smc::machining;

TEST(Simulator, InternalStepDividesTheSample) {
  mc::MillSimulator sim(mc::paper_case());
  EXPECT_EQ(sim.steps_per_sample(), 50);
  EXPECT_DOUBLE_EQ(sim.internal_step_s(), 1e-5);
  mc::SimulatorOptions o;
  o.sample_period_s = 0.5e-3;
  o.max_internal_step_s = 3e-6;
  mc::MillSimulator fine(mc::paper_case(), o);
  EXPECT_EQ(fine.steps_per_sample(), 167);
  EXPECT_LE(fine.internal_step_s(), 3e-6);
}

TEST(Simulator, ContactStartsAtThePartAndEndsWhenTheCutterLeavesIt) {
  const mc::MillingModel m = mc::paper_case();  // part x in [0, 150], 48 mm wide
  mc::MillSimulator sim(m);
  sim.set_tool_position(-m.cutter.radius_mm - 5);
  mc::Sample s;
  double first = std::nan(""), last = std::nan("");
  double prev_position = sim.tool_position_mm();
  for (int k = 0; k < 40000 && sim.tool_position_mm() < 200; ++k) {
    sim.step({10, 1500, 1.0}, s);
    EXPECT_NEAR(s.tool_position_mm - prev_position, 10 * 0.5e-3, 1e-12);
    prev_position = s.tool_position_mm;
    if (s.mean_power_w > 0) {
      if (std::isnan(first)) first = s.tool_position_mm;
      last = s.tool_position_mm;
    }
  }
  // The leading edge (theta = 0) reaches x = 0 when the axis is at -R; a tooth
  // passes theta = 0 within one tooth period (0.1 mm of travel).
  EXPECT_GE(first, -25.0);
  EXPECT_LE(first, -24.85);
  // The last material is at the part's corners (y = +-24): the axis leaves
  // it at x = L - R cos(asin(24/25)) = 150 - 7.
  EXPECT_NEAR(last, 150 - 7.0, 0.15);
}

TEST(Simulator, FeedHoldKeepsTheCutterInPlaceAndStopsCutting) {
  mc::SimulatorOptions o;
  o.initial_tool_position_mm = 40;
  mc::MillSimulator sim(mc::paper_case(), o);
  mc::Sample s;
  for (int k = 0; k < 400; ++k) sim.step({10, 1500, 1.0}, s);
  EXPECT_GT(s.teeth_in_cut, 0);
  EXPECT_GT(s.power_w, 100);
  const double x = sim.tool_position_mm();
  for (int k = 0; k < 400; ++k) sim.step({0, 1500, 1.0}, s);
  EXPECT_DOUBLE_EQ(sim.tool_position_mm(), x);
  EXPECT_EQ(s.feed_per_tooth_mm, 0);
  EXPECT_EQ(s.teeth_in_cut, 0);  // no feed, no chip once the vibration has died out
  EXPECT_NEAR(s.fy_n, 0, 1e-6);
  EXPECT_EQ(s.status, 0u);
  // Feeding again resumes the cut.
  for (int k = 0; k < 100; ++k) sim.step({10, 1500, 1.0}, s);
  EXPECT_GT(s.power_w, 100);
}

TEST(Simulator, IsDeterministic) {
  const auto run = [] {
    mc::SimulatorOptions o;
    o.initial_tool_position_mm = -30;
    mc::MillSimulator sim(mc::paper_case(), o);
    std::vector<double> trace;
    mc::Sample s;
    for (int k = 0; k < 6000; ++k) {
      const double rpm = 1400 + 200 * std::sin(k * 1e-3);
      const double feed = k % 2000 < 1500 ? 12.0 : 0.0;
      sim.step({feed, rpm, 2.0}, s);
      trace.insert(trace.end(), {s.fx_n, s.fy_n, s.fz_n, s.power_w, s.tool_x_mm, s.part_y_mm});
    }
    return trace;
  };
  const std::vector<double> a = run();
  const std::vector<double> b = run();
  ASSERT_EQ(a.size(), b.size());
  EXPECT_EQ(std::memcmp(a.data(), b.data(), a.size() * sizeof(double)), 0);
}

TEST(Simulator, ReportsBadInputsThroughTheStatus) {
  mc::SimulatorOptions o;
  o.initial_tool_position_mm = 40;
  o.min_spindle_rpm = 1000;
  mc::MillSimulator sim(mc::paper_case(), o);
  mc::Sample s;
  for (int k = 0; k < 100; ++k) sim.step({10, 1500, 1.0}, s);
  const double x = sim.tool_position_mm();
  EXPECT_EQ(sim.step({std::nan(""), 1500, 1.0}, s), mc::StepStatus::kInvalidInput);
  EXPECT_EQ(sim.step({10, -1, 1.0}, s), mc::StepStatus::kInvalidInput);
  EXPECT_EQ(sim.step({10, 1500, std::numeric_limits<double>::infinity()}, s),
            mc::StepStatus::kInvalidInput);
  EXPECT_DOUBLE_EQ(sim.tool_position_mm(), x);  // did not move
  EXPECT_EQ(s.teeth_in_cut, 0);
  EXPECT_EQ(sim.step({10, 500, 1.0}, s) & mc::StepStatus::kBelowMinSpindle,
            mc::StepStatus::kBelowMinSpindle);
  EXPECT_EQ(sim.step({10, 0, 1.0}, s), mc::StepStatus::kSpindleStoppedInCut);
  EXPECT_EQ(sim.step({10, 1500, 1.0}, s), 0u);
  // Construction validates.
  mc::MillingModel bad = mc::paper_case();
  bad.cutter.teeth = 0;
  EXPECT_THROW(mc::MillSimulator{bad}, mc::ModelError);
  mc::SimulatorOptions bad_options;
  bad_options.sample_period_s = -1;
  EXPECT_THROW(mc::MillSimulator(mc::paper_case(), bad_options), std::invalid_argument);
}

TEST(Simulator, StepNeverAllocates) {
  mc::SimulatorOptions o;
  o.initial_tool_position_mm = -30;
  o.min_spindle_rpm = 200;
  mc::MillSimulator sim(mc::paper_case(), o);
  mc::Sample s;
  smc::test::ForbidAllocations guard;
  for (int k = 0; k < 4000; ++k) {
    // Speed, feed and depth changing, a feed hold, invalid input, a reset.
    const double rpm = k < 3000 ? 1500 - 0.4 * k : 150;
    sim.step({k % 700 < 600 ? 10.0 : 0.0, rpm, 1.0 + (k % 500) * 0.002}, s);
    if (k == 2500) sim.step({std::nan(""), 1500, 1}, s);
    if (k == 3500) {
      sim.reset();
      sim.set_tool_position(10);
    }
  }
  EXPECT_EQ(guard.violations(), 0u);
}

TEST(Simulator, TraceHoldsEveryInternalStepsForce) {
  // One call per sample with a trace against one call per internal step: the
  // same cut, the same forces step by step (up to the rounding of the spindle
  // angle's recurrence, which the two advance in different chunks), and the
  // trace's last value is the sample's force.
  mc::MillingModel m = mc::paper_case();
  mc::SimulatorOptions per_sample;
  per_sample.forces_at_sample_instant = false;
  per_sample.initial_tool_position_mm = -20;
  mc::SimulatorOptions per_step = per_sample;
  per_step.sample_period_s = 1e-5;
  mc::MillSimulator a(m, per_sample), b(m, per_step);
  ASSERT_EQ(a.steps_per_sample(), 50);
  std::vector<double> fx(50, std::nan("")), fy(50, std::nan("")), fz(50, std::nan(""));
  const mc::StepForceTrace trace{fx.data(), fy.data(), fz.data()};
  mc::Sample sa, sb;
  double worst = 0, largest = 0;
  for (int k = 0; k < 400; ++k) {  // 0.2 s: entry into the part, then a steady cut
    const mc::SampleInput in{10, 1500, k < 200 ? 1.0 : 1.2};
    ASSERT_EQ(a.step(in, sa, trace), 0u);
    for (std::size_t i = 0; i < 50; ++i) {
      ASSERT_EQ(b.step(in, sb), 0u);
      worst = std::max(
          {worst, std::abs(fx[i] - sb.fx_n), std::abs(fy[i] - sb.fy_n), std::abs(fz[i] - sb.fz_n)});
      largest = std::max(largest, std::abs(sb.fy_n));
    }
    EXPECT_EQ(fx[49], sa.fx_n);
    EXPECT_EQ(fy[49], sa.fy_n);
    EXPECT_EQ(fz[49], sa.fz_n);
  }
  EXPECT_GT(largest, 100);  // it did cut
  EXPECT_LT(worst, 1e-6 * largest);
}

TEST(Simulator, TracedStepNeverAllocatesAndNeverPassesOnANonFiniteForce) {
  mc::SimulatorOptions o;
  o.initial_tool_position_mm = 10;
  mc::MillSimulator sim(mc::paper_case(), o);
  std::vector<double> fx(50), fy(50), fz(50);
  const mc::StepForceTrace trace{fx.data(), fy.data(), fz.data()};
  mc::Sample s;
  {
    smc::test::ForbidAllocations guard;
    for (int k = 0; k < 200; ++k) sim.step({10, 1500, 1.0}, s, trace);
    EXPECT_EQ(guard.violations(), 0u);
  }
  EXPECT_GT(std::abs(fy[10]), 100);
  // A linear law at an absurd depth makes the force overflow: the state is
  // reset, the status says so, and the trace holds zeros, never an infinity
  // or a NaN.
  mc::MillingModel lin = mc::paper_case();
  lin.law = mc::LinearLaw{600, 200, 50};
  mc::MillSimulator hot(lin, o);
  bool blew_up = false;
  for (int k = 0; k < 100 && !blew_up; ++k) {
    blew_up = (hot.step({10, 1500, 1e306}, s, trace) & mc::StepStatus::kNotFinite) != 0;
    for (std::size_t i = 0; i < 50; ++i) {
      ASSERT_TRUE(std::isfinite(fx[i]) && std::isfinite(fy[i]) && std::isfinite(fz[i]));
    }
  }
  ASSERT_TRUE(blew_up);
  for (std::size_t i = 0; i < 50; ++i) EXPECT_EQ(fy[i], 0.0);
}

TEST(Simulator, AgreesWithTheBatchRunAtConstantConditions) {
  // Same internal step (1e-5 s divides both the sample and the tooth period),
  // same angles: the stepping simulator inside the part and a steady batch run
  // give the same forces.
  const mc::MillingModel m = mc::paper_case();
  mc::SimulatorOptions so;
  so.initial_tool_position_mm = 50;
  mc::MillSimulator sim(m, so);
  mc::BatchOptions bo;
  bo.duration_s = 0.2;
  bo.record_every_s = 0.5e-3;
  const mc::BatchResult r = mc::simulate(m, mc::CutConditions{1500, 0.1, 1.0}, bo);
  ASSERT_EQ(r.internal_step_s, sim.internal_step_s());
  mc::Sample s;
  double worst = 0;
  for (std::size_t k = 0; k < r.fy_n.size(); ++k) {
    sim.step({10, 1500, 1.0}, s);
    worst = std::max({worst, std::abs(s.fy_n - r.fy_n[k]), std::abs(s.fx_n - r.fx_n[k])});
    EXPECT_NEAR(s.time_s, r.time_s[k], 1e-12);
  }
  EXPECT_LT(worst, 1e-6);
}

TEST(Simulator, TwoMillimetresChatterOneMillimetreDoesNot) {
  const auto vibration = [](double depth) {
    mc::SimulatorOptions o;
    o.initial_tool_position_mm = 0;
    mc::MillSimulator sim(mc::paper_case(), o);
    mc::Sample s;
    double lo = 1e9, hi = -1e9;
    for (int k = 0; k < 2000; ++k) {  // 1 s
      sim.step({10, 1500, depth}, s);
      if (k >= 1600) {  // the last 0.2 s: relative displacement range along y
        lo = std::min(lo, s.tool_y_mm - s.part_y_mm);
        hi = std::max(hi, s.tool_y_mm - s.part_y_mm);
      }
    }
    return hi - lo;
  };
  const double one = vibration(1.0);
  const double two = vibration(2.0);
  EXPECT_GT(two, 5 * 2 * one) << "1 mm: " << one << " mm, 2 mm: " << two << " mm";
}

// Without regeneration the same 2 mm cut is the forced response alone: it
// repeats every revolution, as the 1 mm cut does, and vibrates more than
// the 1 mm cut but a fraction of what its chatter does.
TEST(Simulator, WithoutRegenerationTheChatteringCutRepeatsItself) {
  const auto vibration = [](double depth, bool regenerative, double* change) {
    mc::SimulatorOptions o;
    o.regenerative = regenerative;
    mc::MillSimulator sim(mc::paper_case(), o);
    mc::Sample s;
    std::vector<double> y;
    for (int k = 0; k < 2000; ++k) {  // 1 s; 1500 rpm is 80 samples a revolution
      sim.step({10, 1500, depth}, s);
      y.push_back(s.tool_y_mm - s.part_y_mm);
    }
    // The last 0.2 s against the same samples a revolution earlier.
    double diff = 0, energy = 0, lo = 1e9, hi = -1e9;
    for (size_t k = 1600; k < y.size(); ++k) {
      diff += (y[k] - y[k - 80]) * (y[k] - y[k - 80]);
      energy += y[k] * y[k];
      lo = std::min(lo, y[k]);
      hi = std::max(hi, y[k]);
    }
    *change = std::sqrt(diff / energy);
    return hi - lo;
  };
  double q_chatter = 0, q_forced = 0, q_one = 0;
  const double chatter = vibration(2.0, true, &q_chatter);
  const double forced = vibration(2.0, false, &q_forced);
  const double one = vibration(1.0, false, &q_one);
  EXPECT_GT(q_chatter, 0.3) << "with regeneration the 2 mm cut chatters";
  EXPECT_LT(q_forced, 0.01);
  EXPECT_LT(q_one, 0.01);
  EXPECT_LT(forced, chatter / 5);
  EXPECT_GT(forced, 1.5 * one);
}
