#pragma once
// Notes on a machine's wideband F_y channel: where its anti-alias filter
// takes a y mode of a structure E would undo on that machine so far down
// that E would miss the mode's chatter (smc::supervision::
// wideband_channel_warning; edge/CHATTER.md, "What the channel's filter
// costs E"). `smc-cell catalog apply` prints them for the documents it
// applies, `part show` beside each machine, and the cell's catalog view
// carries them to dashboards. The record is accepted all the same: the
// sensor is what it is.

#include <string>
#include <vector>

#include "smc/cell/store/entities.hpp"

namespace smc::cell {
namespace store {
class Store;
}

// A structure E could undo on a machine: a milling model's.
struct StructureOf {
  std::string model_id;
  const smc::config::Structure* structure = nullptr;
};

struct ChannelNote {
  std::string model_id;  // the first model whose structure gives the text
  std::string text;      // the warning, with its fix
};

// Appends the structures of the milling models among `models` (which must
// outlive `out`: it points into them).
void add_milling_structures(const std::vector<store::ProcessModel>& models,
                            std::vector<StructureOf>& out);

// The channel against each structure, one note per distinct text. None for
// the cell's default channel (samples_per_tick 0).
std::vector<ChannelNote> channel_notes(const store::WidebandChannel& channel,
                                       const std::vector<StructureOf>& structures);

// The same for a machine of the database, against its milling models.
std::vector<ChannelNote> channel_notes(store::Store& db, const store::Machine& machine);

}  // namespace smc::cell
