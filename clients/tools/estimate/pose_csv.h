#pragma once

// The pose file of `shapesense estimate`: CSV with a header naming the
// columns, then one pose per line:
//
//   y0,y1,...,y(n-1),kappa_x,kappa_z,eps0,eps1[,tau0,...,tau(n-1)]
//
// commanded displacements (mm), sensed configuration (1/mm, 1/mm, -, -) and
// optionally measured tensions (N). Columns may come in any order; other
// columns (a time stamp, say) are ignored. Blank lines and lines starting
// with '#' are skipped.

#include <string>
#include <vector>

#include "libs/mechanics/stiffness_estimation.h"

namespace shapesense {

// Throws InputError naming `source`, the line and the column: a missing or
// repeated column, a tendon column the model does not have, a line with the
// wrong number of fields, a field that is not a finite number.
std::vector<PoseSample> ParsePoseCsv(const std::string& text, const std::string& source,
                                     int num_tendons, bool with_tensions);

// The same format, with tensions when every pose has them (tests, tools).
std::string FormatPoseCsv(const std::vector<PoseSample>& poses);

}  // namespace shapesense
