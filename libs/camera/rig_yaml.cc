#include "libs/camera/rig_yaml.h"

#include <opencv2/core.hpp>
#include <opencv2/core/eigen.hpp>

#include "libs/core/error.h"

namespace shapesense {
namespace {

// Reads one key of a FileStorage map with the error naming source and key.
class NodeReader {
 public:
  NodeReader(cv::FileNode node, std::string source, std::string path)
      : node_(node), source_(std::move(source)), path_(std::move(path)) {}

  [[noreturn]] void Fail(const std::string& key, const std::string& what) const {
    throw InputError(DescribeInputError(source_, path_ + key, what));
  }

  cv::FileNode Required(const std::string& key) const {
    cv::FileNode child = node_[key];
    if (child.empty()) Fail(key, "missing");
    return child;
  }

  Eigen::MatrixXd Matrix(const std::string& key, int rows, int cols) const {
    cv::Mat mat;
    try {
      Required(key) >> mat;
    } catch (const cv::Exception&) {
      Fail(key, "expected an OpenCV matrix (!!opencv-matrix)");
    }
    if (mat.empty()) Fail(key, "expected an OpenCV matrix (!!opencv-matrix)");
    if (mat.total() != static_cast<size_t>(rows * cols) || mat.channels() != 1) {
      Fail(key, "expected " + std::to_string(rows) + "x" + std::to_string(cols) + " values, got " +
                    std::to_string(mat.rows) + "x" + std::to_string(mat.cols));
    }
    cv::Mat as_double;
    mat.reshape(1, rows).convertTo(as_double, CV_64F);
    Eigen::MatrixXd out;
    cv::cv2eigen(as_double, out);
    if (!out.allFinite()) Fail(key, "expected finite numbers");
    return out;
  }

  Vec3 Vector3(const std::string& key) const {
    cv::FileNode child = Required(key);
    if (child.isSeq() && child.size() == 3) {
      Vec3 v;
      for (int i = 0; i < 3; ++i) v[i] = static_cast<double>(child[i]);
      return v;
    }
    return Matrix(key, 1, 3).transpose();
  }

  int PositiveInt(const std::string& key) const {
    cv::FileNode child = Required(key);
    if (!child.isInt() || static_cast<int>(child) <= 0) Fail(key, "expected a positive integer");
    return static_cast<int>(child);
  }

  std::string String(const std::string& key) const {
    cv::FileNode child = Required(key);
    if (!child.isString() || child.string().empty()) Fail(key, "expected a non-empty string");
    return child.string();
  }

 private:
  cv::FileNode node_;
  std::string source_;
  std::string path_;
};

Camera ReadCamera(const NodeReader& reader, bool with_pose) {
  Camera camera;
  camera.name = with_pose ? reader.String("name") : "";
  camera.width = reader.PositiveInt("image_width");
  camera.height = reader.PositiveInt("image_height");
  camera.camera_matrix = reader.Matrix("camera_matrix", 3, 3);
  const Eigen::MatrixXd d = reader.Matrix("distortion_coefficients", 1, 5);
  for (int i = 0; i < 5; ++i) camera.distortion[static_cast<size_t>(i)] = d(0, i);
  if (with_pose) {
    camera.cam_from_world.linear() = reader.Matrix("rotation", 3, 3);
    camera.cam_from_world.translation() = reader.Matrix("translation", 3, 1);
  }
  return camera;
}

cv::FileStorage OpenText(const std::string& text, const std::string& source) {
  cv::FileStorage storage;
  try {
    storage.open(text,
                 cv::FileStorage::READ | cv::FileStorage::MEMORY | cv::FileStorage::FORMAT_YAML);
  } catch (const cv::Exception& e) {
    throw InputError(source + ": not valid OpenCV FileStorage YAML (" + e.err + ")");
  }
  if (!storage.isOpened()) throw InputError(source + ": not valid OpenCV FileStorage YAML");
  return storage;
}

void WriteCamera(cv::FileStorage& out, const Camera& camera, bool with_pose) {
  if (with_pose) out << "name" << camera.name;
  out << "image_width" << camera.width << "image_height" << camera.height;
  cv::Mat k, d(1, 5, CV_64F), r, t;
  cv::eigen2cv(camera.camera_matrix, k);
  for (int i = 0; i < 5; ++i) d.at<double>(0, i) = camera.distortion[static_cast<size_t>(i)];
  out << "camera_matrix" << k << "distortion_coefficients" << d;
  if (with_pose) {
    const Mat3 rotation = camera.cam_from_world.linear();
    const Vec3 translation = camera.cam_from_world.translation();
    cv::eigen2cv(rotation, r);
    cv::eigen2cv(translation, t);
    out << "rotation" << r << "translation" << t;
  }
}

cv::Mat RowVector(const Vec3& v) { return (cv::Mat_<double>(1, 3) << v.x(), v.y(), v.z()); }

}  // namespace

Rig ParseRigYaml(const std::string& text, const std::string& source) {
  cv::FileStorage storage = OpenText(text, source);
  const NodeReader root(storage.root(), source, "");
  const cv::FileNode cameras = root.Required("cameras");
  if (!cameras.isSeq() || cameras.size() == 0) {
    root.Fail("cameras", "expected a non-empty sequence of camera maps");
  }
  Rig rig;
  for (size_t i = 0; i < cameras.size(); ++i) {
    const NodeReader reader(cameras[static_cast<int>(i)], source,
                            "cameras[" + std::to_string(i) + "].");
    rig.cameras.push_back(ReadCamera(reader, /*with_pose=*/true));
  }
  rig.workspace_min = root.Vector3("workspace_min");
  rig.workspace_max = root.Vector3("workspace_max");
  rig.base_point = root.Vector3("base_point");
  if (const std::string error = rig.Validate(); !error.empty()) {
    throw InputError(source + ": " + error);
  }
  return rig;
}

std::string FormatRigYaml(const Rig& rig) {
  cv::FileStorage out(".yaml", cv::FileStorage::WRITE | cv::FileStorage::MEMORY);
  out << "cameras"
      << "[";
  for (const Camera& camera : rig.cameras) {
    out << "{";
    WriteCamera(out, camera, /*with_pose=*/true);
    out << "}";
  }
  out << "]";
  out << "workspace_min" << RowVector(rig.workspace_min);
  out << "workspace_max" << RowVector(rig.workspace_max);
  out << "base_point" << RowVector(rig.base_point);
  return out.releaseAndGetString();
}

Camera ParseCameraYaml(const std::string& text, const std::string& source) {
  cv::FileStorage storage = OpenText(text, source);
  const NodeReader root(storage.root(), source, "");
  Camera camera = ReadCamera(root, /*with_pose=*/false);
  camera.name = storage["name"].isString() ? storage["name"].string() : "camera";
  if (const std::string error = camera.Validate(); !error.empty()) {
    throw InputError(source + ": " + error);
  }
  return camera;
}

std::string FormatCameraYaml(const Camera& camera) {
  cv::FileStorage out(".yaml", cv::FileStorage::WRITE | cv::FileStorage::MEMORY);
  out << "name" << camera.name;
  WriteCamera(out, camera, /*with_pose=*/false);
  return out.releaseAndGetString();
}

}  // namespace shapesense
