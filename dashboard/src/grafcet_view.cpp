#include "grafcet_view.hpp"

#include "json.hpp"
#include "smc/grafcet/model.hpp"
#include "smc/grafcet/parser.hpp"

namespace smc::dashboard {

namespace {

void write_step_numbers(JsonWriter& w, const grafcet::Grafcet& g, grafcet::Mask steps) {
  w.begin_array();
  for (size_t i = 0; i < g.steps().size(); ++i) {
    if ((steps >> i) & 1U) w.value(g.steps()[i].number);
  }
  w.end_array();
}

void write_actions(JsonWriter& w, const grafcet::Grafcet& g, const grafcet::Step& step) {
  w.begin_array();
  for (size_t i = 0; i < g.actions().size(); ++i) {
    const bool level = (step.level_actions >> i) & 1U;
    const bool impulse = (step.impulse_actions >> i) & 1U;
    if (!level && !impulse) continue;
    w.begin_object().field("name", g.actions()[i].name).field("impulse", impulse && !level);
    w.end_object();
  }
  w.end_array();
}

}  // namespace

GrafcetView make_grafcet_view(std::string_view text, std::string_view source) {
  GrafcetView view;
  JsonWriter w;
  const grafcet::ParseResult parsed = grafcet::parse(text, source);
  if (!parsed.ok()) {
    w.begin_object().field("ok", false).key("errors").begin_array();
    for (const auto& e : parsed.errors) w.value(e.str());
    w.end_array().end_object();
    view.json = w.take();
    return view;
  }
  const grafcet::Grafcet& g = *parsed.grafcet;
  view.ok = true;
  w.begin_object().field("ok", true).field("name", g.name()).field("title", g.title());
  w.key("inputs").begin_array();
  for (const auto& in : g.inputs()) {
    view.input_names.push_back(in.name);
    w.begin_object().field("name", in.name).field("description", in.description).end_object();
  }
  w.end_array();
  w.key("actions").begin_array();
  for (const auto& a : g.actions()) {
    w.begin_object().field("name", a.name).field("description", a.description).end_object();
  }
  w.end_array();
  w.key("steps").begin_array();
  for (size_t i = 0; i < g.steps().size(); ++i) {
    const auto& s = g.steps()[i];
    view.step_numbers.push_back(s.number);
    w.begin_object()
        .field("index", i)
        .field("number", s.number)
        .field("label", s.label)
        .field("initial", s.initial);
    w.key("actions");
    write_actions(w, g, s);
    w.end_object();
  }
  w.end_array();
  w.key("transitions").begin_array();
  for (const auto& t : g.transitions()) {
    w.begin_object().field("number", t.number);
    w.key("from");
    write_step_numbers(w, g, t.preceding);
    w.key("to");
    write_step_numbers(w, g, t.following);
    w.field("receptivity", t.receptivity.text).end_object();
  }
  w.end_array();
  w.key("orders").begin_array();
  for (const auto& o : g.orders()) {
    w.begin_object().field("step", g.steps()[o.step].number).key("transitions").begin_array();
    for (const size_t t : o.transitions) w.value(g.transitions()[t].number);
    w.end_array().end_object();
  }
  w.end_array();
  w.end_object();
  view.json = w.take();
  return view;
}

std::vector<std::uint32_t> active_step_numbers(const GrafcetView& view, std::uint64_t mask) {
  std::vector<std::uint32_t> out;
  for (unsigned i = 0; i < 64; ++i) {
    if (((mask >> i) & 1U) == 0) continue;
    out.push_back(i < view.step_numbers.size() ? view.step_numbers[i] : 0U);
  }
  return out;
}

}  // namespace smc::dashboard
