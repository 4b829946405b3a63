// Plain-text tables for terminal listings (list-cameras, ...): columns left-aligned at widths
// computed from the cells, so that every column starts at the same place on every row.
#pragma once

#include <string>
#include <vector>

namespace fetchscope {

/// `rows` (each a list of cells; rows may have fewer cells than others) as lines ending in '\n':
/// every column but a row's last is padded to the widest cell of that column plus `gap` spaces.
/// Widths count UTF-8 code points, not bytes. Nothing trails a row's last cell.
std::string AlignColumns(const std::vector<std::vector<std::string>>& rows, int gap = 2);

}  // namespace fetchscope
