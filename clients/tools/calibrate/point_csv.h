#pragma once

// Point lists as CSV, mm: one point a line, "x,y,z" or "name,x,y,z". Blank
// lines and lines starting with '#' are skipped; a first line that is not
// numbers is taken as a header (e.g. "name,x,y,z").

#include <string>
#include <vector>

#include "libs/geometry/types.h"

namespace shapesense {

struct NamedPoint {
  std::string name;  // empty in the "x,y,z" form
  Vec3 position = Vec3::Zero();
};

// Throws InputError "source:line: what" on a line that is not a point, and
// when the file holds no point or mixes the two forms.
std::vector<NamedPoint> ParsePointCsv(const std::string& text, const std::string& source);

}  // namespace shapesense
