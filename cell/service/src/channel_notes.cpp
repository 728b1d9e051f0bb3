#include "smc/cell/channel_notes.hpp"

#include <set>

#include "smc/cell/store/store.hpp"
#include "smc/supervision/parameters.hpp"

namespace smc::cell {

void add_milling_structures(const std::vector<store::ProcessModel>& models,
                            std::vector<StructureOf>& out) {
  for (const auto& m : models) {
    if (m.kind == store::ModelKind::kMilling) out.push_back({m.id, &m.milling.structure()});
  }
}

std::vector<ChannelNote> channel_notes(const store::WidebandChannel& channel,
                                       const std::vector<StructureOf>& structures) {
  std::vector<ChannelNote> notes;
  if (channel.is_default()) return notes;
  std::set<std::string> seen;
  for (const auto& s : structures) {
    if (s.structure == nullptr) continue;
    auto text = smc::supervision::wideband_channel_warning(channel.rate_hz(), channel.cutoff_hz,
                                                           channel.order(), *s.structure);
    if (text.empty() || !seen.insert(text).second) continue;
    notes.push_back({s.model_id, std::move(text)});
  }
  return notes;
}

std::vector<ChannelNote> channel_notes(store::Store& db, const store::Machine& machine) {
  if (machine.wideband.is_default()) return {};
  const auto models = db.find_models(machine.id, "", "", "");
  std::vector<StructureOf> structures;
  add_milling_structures(models, structures);
  return channel_notes(machine.wideband, structures);
}

}  // namespace smc::cell
