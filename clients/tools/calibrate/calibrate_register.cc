// `shapesense calibrate register`: the rigid transform between points the
// system sensed and the same points measured by a reference digitizer, and
// the error per axis, as in the reference's accuracy validation.
#include <Eigen/Core>  // before opencv2/core/eigen.hpp
#include <cstdio>
#include <iomanip>
#include <map>
#include <opencv2/core.hpp>
#include <opencv2/core/eigen.hpp>
#include <sstream>

#include "clients/tools/calibrate/calibrate_command.h"
#include "clients/tools/calibrate/point_csv.h"
#include "libs/calibration/calibration_drawing.h"
#include "libs/core/error.h"
#include "runtime/file_io.h"

namespace shapesense {
namespace fs = std::filesystem;
namespace {

struct PointPairs {
  std::vector<std::string> names;
  std::vector<Vec3> reference;
  std::vector<Vec3> sensed;
};

// By name when both files name their points, else line by line.
PointPairs MatchPoints(const std::vector<NamedPoint>& reference,
                       const std::vector<NamedPoint>& sensed, const RegisterArgs& args) {
  PointPairs pairs;
  const bool named = !reference[0].name.empty() && !sensed[0].name.empty();
  if (!named) {
    if (reference.size() != sensed.size()) {
      throw InputError(args.sensed.string() + ": " + std::to_string(sensed.size()) +
                       " points, but " + args.reference.string() + " has " +
                       std::to_string(reference.size()) + "; unnamed points pair line by line");
    }
    for (size_t i = 0; i < reference.size(); ++i) {
      pairs.names.push_back(reference[i].name.empty() ? std::to_string(i + 1) : reference[i].name);
      pairs.reference.push_back(reference[i].position);
      pairs.sensed.push_back(sensed[i].position);
    }
    return pairs;
  }
  std::map<std::string, Vec3> by_name;
  for (const NamedPoint& point : sensed) by_name[point.name] = point.position;
  for (const NamedPoint& point : reference) {
    const auto found = by_name.find(point.name);
    if (found == by_name.end()) {
      throw InputError(args.sensed.string() + ": no point '" + point.name + "' (named in " +
                       args.reference.string() + ")");
    }
    pairs.names.push_back(point.name);
    pairs.reference.push_back(point.position);
    pairs.sensed.push_back(found->second);
  }
  return pairs;
}

cv::Mat Row(const Vec3& v) { return (cv::Mat_<double>(1, 3) << v.x(), v.y(), v.z()); }

std::string RegistrationYaml(const PointPairs& pairs, const PointRegistration& r) {
  cv::FileStorage out(".yaml", cv::FileStorage::WRITE | cv::FileStorage::MEMORY);
  cv::Mat rotation, translation;
  cv::eigen2cv(Mat3(r.reference_from_sensed.linear()), rotation);
  cv::eigen2cv(Vec3(r.reference_from_sensed.translation()), translation);
  out << "reference_from_sensed_rotation" << rotation;
  out << "reference_from_sensed_translation" << translation;
  out << "rms_per_axis" << Row(r.rms_per_axis) << "rms" << r.rms << "max_error" << r.max_error;
  out << "points"
      << "[";
  for (size_t i = 0; i < pairs.names.size(); ++i) {
    out << "{"
        << "name" << pairs.names[i] << "reference" << Row(pairs.reference[i]) << "sensed"
        << Row(pairs.sensed[i]) << "error" << Row(r.errors[i]) << "}";
  }
  out << "]";
  return out.releaseAndGetString();
}

std::string Fixed(double value, int digits = 3) {
  std::ostringstream out;
  out << std::fixed << std::setprecision(digits) << value;
  return out.str();
}

std::string ReportMarkdown(const RegisterArgs& args, const PointPairs& pairs,
                           const PointRegistration& r) {
  std::ostringstream md;
  const Eigen::AngleAxisd turn(Mat3(r.reference_from_sensed.linear()));
  const Vec3 t = r.reference_from_sensed.translation();
  md << "# Registration to the reference digitizer\n\n"
     << "Reference: `" << args.reference.string() << "`; sensed: `" << args.sensed.string() << "`; "
     << pairs.names.size() << " points.\n\n"
     << "## Transform (reference_from_sensed)\n\n"
     << "Rotation " << Fixed(turn.angle() * 180.0 / 3.14159265358979323846, 4) << " deg about ("
     << Fixed(turn.axis().x(), 4) << ", " << Fixed(turn.axis().y(), 4) << ", "
     << Fixed(turn.axis().z(), 4) << "); translation (" << Fixed(t.x()) << ", " << Fixed(t.y())
     << ", " << Fixed(t.z()) << ") mm.\n\n"
     << "## Error, mm (reference frame)\n\n| | x | y | z | 3-D |\n|---|---|---|---|---|\n"
     << "| RMS | " << Fixed(r.rms_per_axis.x()) << " | " << Fixed(r.rms_per_axis.y()) << " | "
     << Fixed(r.rms_per_axis.z()) << " | " << Fixed(r.rms) << " |\n\n"
     << "Largest 3-D error: " << Fixed(r.max_error) << " mm.\n\n![errors](registration.png)\n\n"
     << "## Per point\n\n| point | x | y | z | 3-D |\n|---|---|---|---|---|\n";
  for (size_t i = 0; i < pairs.names.size(); ++i) {
    const Vec3& e = r.errors[i];
    md << "| " << pairs.names[i] << " | " << Fixed(e.x()) << " | " << Fixed(e.y()) << " | "
       << Fixed(e.z()) << " | " << Fixed(e.norm()) << " |\n";
  }
  return md.str();
}

}  // namespace

RegisterReport RunCalibrateRegister(const RegisterArgs& args, std::ostream& log) {
  if (const std::string error = args.options.Validate(); !error.empty()) {
    throw InputError("register options: " + error);
  }
  const std::vector<NamedPoint> reference =
      ParsePointCsv(ReadTextFile(args.reference), args.reference.string());
  const std::vector<NamedPoint> sensed =
      ParsePointCsv(ReadTextFile(args.sensed), args.sensed.string());
  const PointPairs pairs = MatchPoints(reference, sensed, args);
  RegisterReport report;
  try {
    report.registration = RegisterPoints(pairs.sensed, pairs.reference, args.options);
  } catch (const InputError& e) {
    throw InputError(args.sensed.string() + " against " + args.reference.string() + ": " +
                     e.what());
  }
  report.point_names = pairs.names;
  const PointRegistration& r = report.registration;
  log << pairs.names.size() << " points; error RMS x " << Fixed(r.rms_per_axis.x()) << "  y "
      << Fixed(r.rms_per_axis.y()) << "  z " << Fixed(r.rms_per_axis.z()) << "  3-D "
      << Fixed(r.rms) << " mm; largest " << Fixed(r.max_error) << " mm\n";
  fs::create_directories(args.out);
  WriteFileAtomically(args.out / "registration.yaml", RegistrationYaml(pairs, r));
  WritePng(args.out / "registration.png", DrawRegistrationPlot(pairs.reference, r));
  WriteFileAtomically(args.out / "report.md", ReportMarkdown(args, pairs, r));
  log << "wrote " << (args.out / "report.md").string()
      << ", registration.yaml and registration.png\n";
  return report;
}

}  // namespace shapesense
