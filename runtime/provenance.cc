#include "runtime/provenance.h"

#include <ctime>

#include "runtime/file_io.h"
#include "shapesense_version.h"

namespace shapesense {

std::string ProjectVersion() { return SHAPESENSE_VERSION; }

std::string UtcNow() {
  const std::time_t now = std::time(nullptr);
  std::tm utc{};
  gmtime_r(&now, &utc);
  char text[32];
  std::strftime(text, sizeof(text), "%FT%TZ", &utc);
  return text;
}

void WriteEffectiveConfig(const std::filesystem::path& path, const std::string& what,
                          const std::string& options_yaml) {
  WriteFileAtomically(path, "# " + what + "\n# shapesense " + ProjectVersion() + ", " + UtcNow() +
                                "\n# the effective options (defaults included); --config takes "
                                "this file back as it is\n" +
                                options_yaml);
}

}  // namespace shapesense
