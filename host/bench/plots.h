#pragma once
// Plots of a result set (PNG through OpenImageIO), drawn from the same cell records as the tables.
// Every speedup carries its 95 % interval as an error bar; cells whose order equals NoSort's are
// left out (no speedup is reported for them). File names carry -fast / -permute for those facets.
//   speed-vs-bits-<scene>-<batch>.png   trace speedup against key bits, one line (colour and
//                                       marker) per encoder;
//   overhead-vs-gain-<batch>-<bits>b.png trace speedup against encode + sort (+ permute) overhead:
//                                       "what accuracy costs in time" at a glance, colour =
//                                       encoder, marker shape = scene, with the break-even curve
//                                       (net speedup 1) drawn in.
#include <string>
#include <vector>

#include "bench/record.h"

namespace raysort {

// Writes the plots into dir; returns the file names written. Plots need a TrueType font
// (fonts-dejavu-core); without one, they are drawn without text.
std::vector<std::string> write_plots(const std::vector<CellRecord>& cells, const std::string& dir);

}  // namespace raysort
