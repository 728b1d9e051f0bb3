#pragma once
// Helpers shared by the Grafcet tests.

#include <gtest/gtest.h>

#include <bit>
#include <string>
#include <string_view>

#include "smc/grafcet/engine.hpp"
#include "smc/grafcet/parser.hpp"

namespace smc::grafcet::testing {

inline std::string grafcet_path(std::string_view relative) {
  return std::string(SMC_SOURCE_DIR) + "/cell/grafcets/" + std::string(relative);
}

// Parses text that must be valid; a failure lists the diagnostics.
inline Grafcet parse_ok(std::string_view text) {
  ParseResult r = parse(text, "test.grafcet");
  std::string all;
  for (const Diagnostic& d : r.errors) all += d.str() + "\n";
  if (!r.ok()) ADD_FAILURE() << "unexpected parse errors:\n" << all;
  if (!r.ok()) throw std::runtime_error("parse failed");
  return std::move(*r.grafcet);
}

inline Grafcet load_ok(std::string_view relative) {
  ParseResult r = parse_file(grafcet_path(relative));
  std::string all;
  for (const Diagnostic& d : r.errors) all += d.str() + "\n";
  if (!r.ok()) ADD_FAILURE() << "unexpected parse errors:\n" << all;
  if (!r.ok()) throw std::runtime_error("parse failed");
  return std::move(*r.grafcet);
}

// Input valuation from the names of the true inputs, e.g. inputs(g, "a b").
inline Mask inputs(const Grafcet& g, std::string_view names) {
  Mask m = 0;
  std::size_t i = 0;
  while (i < names.size()) {
    while (i < names.size() && names[i] == ' ') ++i;
    std::size_t j = i;
    while (j < names.size() && names[j] != ' ') ++j;
    if (j > i) {
      const int k = g.input_index(names.substr(i, j - i));
      if (k < 0) throw std::runtime_error("unknown input in test: " + std::string(names));
      m |= Mask{1} << k;
    }
    i = j;
  }
  return m;
}

// Step numbers of a step mask, e.g. "2 5".
inline std::string step_numbers(const Grafcet& g, Mask steps) {
  std::string s;
  for (Mask m = steps; m != 0; m &= m - 1) {
    if (!s.empty()) s += ' ';
    s += std::to_string(g.steps()[static_cast<std::size_t>(std::countr_zero(m))].number);
  }
  return s;
}

// Action names of an action mask in declaration order, e.g. "ABIJ".
inline std::string action_names(const Grafcet& g, Mask actions) {
  std::string s;
  for (Mask m = actions; m != 0; m &= m - 1)
    s += g.actions()[static_cast<std::size_t>(std::countr_zero(m))].name;
  return s;
}

}  // namespace smc::grafcet::testing
