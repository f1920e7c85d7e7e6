#include "tracking/calibration.hpp"

#include <libxml/parser.h>
#include <yaml.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <fstream>
#include <iterator>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string_view>

#include "core/input_error.hpp"

namespace ps::tracking {

namespace {

bool allFinite(const cv::Mat& m) {
  for (int i = 0; i < m.rows; ++i)
    for (int j = 0; j < m.cols; ++j)
      if (!std::isfinite(m.at<double>(i, j))) return false;
  return true;
}

}  // namespace

CameraCalibration CameraCalibration::pinhole(double fx, double fy, double cx, double cy,
                                             cv::Size size) {
  CameraCalibration c;
  c.K = cv::Matx33d(fx, 0, cx, 0, fy, cy, 0, 0, 1);
  c.imageSize = size;
  return c;
}

void CameraCalibration::validate() const {
  const cv::Mat k(K);
  if (!allFinite(k)) throw core::InputError(source + ": camera_matrix is not finite");
  if (!(K(0, 0) > 0) || !(K(1, 1) > 0))
    throw core::InputError(
        source + ": camera_matrix has focal lengths fx = " + core::formatNumber(K(0, 0), 10) +
        ", fy = " + core::formatNumber(K(1, 1), 10) + " (must be > 0)");
  if (K(1, 0) != 0 || K(2, 0) != 0 || K(2, 1) != 0 || K(2, 2) != 1)
    throw core::InputError(source + ": camera_matrix is not of the form [fx s cx; 0 fy cy; 0 0 1]");
  const int n = int(distortion.total());
  if (distortion.type() != CV_64F || (distortion.rows != 1 && distortion.cols != 1) ||
      (n != 4 && n != 5 && n != 8 && n != 12 && n != 14))
    throw core::InputError(source +
                           ": distortion_coefficients must be 1xN or Nx1 with N in "
                           "{4, 5, 8, 12, 14}, not " +
                           std::to_string(distortion.rows) + "x" + std::to_string(distortion.cols));
  if (!allFinite(distortion))
    throw core::InputError(source + ": distortion_coefficients are not finite");
  if (imageSize.width < 0 || imageSize.height < 0 ||
      (imageSize.width == 0) != (imageSize.height == 0))
    throw core::InputError(source + ": image size " + std::to_string(imageSize.width) + "x" +
                           std::to_string(imageSize.height) + " is not valid");
}

CameraCalibration CameraCalibration::forImageSize(cv::Size size) const {
  if (size.width <= 0 || size.height <= 0)
    throw core::InputError("image size " + std::to_string(size.width) + "x" +
                           std::to_string(size.height) + " is not valid");
  CameraCalibration c = *this;
  if (imageSize.width == 0) {
    c.imageSize = size;  // unknown: taken to be the video's
    return c;
  }
  if (imageSize == size) return c;
  const double sx = double(size.width) / imageSize.width;
  const double sy = double(size.height) / imageSize.height;
  if (std::abs(sx / sy - 1.0) > 0.01)
    throw core::InputError(source + ": calibrated for " + std::to_string(imageSize.width) + "x" +
                           std::to_string(imageSize.height) + ", the video is " +
                           std::to_string(size.width) + "x" + std::to_string(size.height) +
                           " (another aspect ratio: a crop cannot be rescaled; calibrate at this"
                           " size)");
  c.K(0, 0) *= sx;
  c.K(0, 1) *= sx;
  c.K(0, 2) = (K(0, 2) + 0.5) * sx - 0.5;
  c.K(1, 1) *= sy;
  c.K(1, 2) = (K(1, 2) + 0.5) * sy - 0.5;
  c.imageSize = size;
  return c;
}

namespace {

// OpenCV 4.6's FileStorage parsers loop forever on some malformed text (fuzz_calibration found
// "%YAML:1.\n t:d\n%Y\n-" and others), so the text must be well-formed before OpenCV reads it:
// JSON by nlohmann-json, XML by libxml2, YAML by libyaml (after OpenCV's own "%YAML:1.0" line,
// which is not a YAML 1.x directive).
void checkWellFormed(const std::string& text, const std::string& name) {
  const std::size_t first = text.find_first_not_of(" \t\r\n");
  if (first == std::string::npos) throw core::InputError(name + ": empty calibration file");
  if (text[first] == '{') {
    if (!nlohmann::json::accept(text))
      throw core::InputError(name + ": malformed calibration file (not valid JSON)");
    return;
  }
  if (text[first] == '<') {
    xmlDocPtr doc =
        xmlReadMemory(text.data(), int(std::min<std::size_t>(text.size(), INT32_MAX)), name.c_str(),
                      nullptr, XML_PARSE_NONET | XML_PARSE_NOERROR | XML_PARSE_NOWARNING);
    if (!doc) throw core::InputError(name + ": malformed calibration file (not well-formed XML)");
    xmlFreeDoc(doc);
    return;
  }
  std::string_view yaml = text;
  int lineOffset = 0;
  if (yaml.rfind("%YAML:", 0) == 0) {
    const std::size_t eol = yaml.find('\n');
    yaml = eol == std::string_view::npos ? std::string_view() : yaml.substr(eol + 1);
    lineOffset = 1;
  }
  yaml_parser_t parser;
  if (!yaml_parser_initialize(&parser)) throw std::runtime_error("libyaml could not start");
  // libyaml asserts on a null input, which an empty view may hold.
  static const char kNothing[] = "";
  yaml_parser_set_input_string(
      &parser, reinterpret_cast<const unsigned char*>(yaml.empty() ? kNothing : yaml.data()),
      yaml.size());
  yaml_document_t doc;
  const bool loaded = yaml_parser_load(&parser, &doc) != 0;
  std::string problem;
  if (!loaded) {
    problem = "YAML line " +
              std::to_string(parser.problem_mark.line + 1 + std::size_t(lineOffset)) + ": " +
              (parser.problem ? parser.problem : "malformed YAML");
  } else {
    // A calibration is a mapping that holds camera_matrix (OpenCV's parser has been seen to loop
    // on other well-formed documents, e.g. a lone multi-line scalar).
    const yaml_node_t* root = yaml_document_get_root_node(&doc);
    bool hasMatrix = false;
    if (root && root->type == YAML_MAPPING_NODE) {
      for (auto* pair = root->data.mapping.pairs.start; pair < root->data.mapping.pairs.top;
           ++pair) {
        const yaml_node_t* key = yaml_document_get_node(&doc, pair->key);
        if (key && key->type == YAML_SCALAR_NODE &&
            std::string_view(reinterpret_cast<const char*>(key->data.scalar.value),
                             key->data.scalar.length) == "camera_matrix")
          hasMatrix = true;
      }
    }
    if (!root || root->type != YAML_MAPPING_NODE) {
      problem = "YAML: not a mapping of calibration fields";
    } else if (!hasMatrix) {
      yaml_document_delete(&doc);
      yaml_parser_delete(&parser);
      throw core::InputError(name + ": no camera_matrix");
    }
    yaml_document_delete(&doc);
  }
  yaml_parser_delete(&parser);
  if (!problem.empty())
    throw core::InputError(name + ": malformed calibration file (" + problem + ")");
}

// Runs `read` with what OpenCV throws (cv::Exception, and the std::length_error its parser lets
// out) turned into InputError naming `name`.
template <class Read>
void translatingOpenCvErrors(const std::string& name, Read&& read) {
  try {
    read();
  } catch (const core::InputError&) {
    throw;
  } catch (const cv::Exception& e) {
    throw core::InputError(name + ": malformed calibration file (" + e.err + ")");
  } catch (const std::exception& e) {
    throw core::InputError(name + ": malformed calibration file (" + e.what() + ")");
  }
}

void openStorage(cv::FileStorage& fs, const std::string& source, int flags,
                 const std::string& name) {
  translatingOpenCvErrors(name, [&] {
    if (!fs.open(source, flags))
      throw core::InputError(name + ": not a calibration file OpenCV can read (YAML/XML/JSON)");
  });
}

// An OpenCV matrix node's declared size, checked before OpenCV allocates for it (a damaged
// "rows" or "cols" once asked for gigabytes): at most 3 x 14 elements, as integers.
void checkMatrixNode(const cv::FileNode& node, const std::string& name, const char* key) {
  if (node.empty() || !node.isMap()) return;  // absent or not a matrix: the reader says which
  const cv::FileNode rows = node["rows"], cols = node["cols"];
  if (!rows.isInt() || !cols.isInt())
    throw core::InputError(name + ": " + key + ": rows and cols must be integers");
  const int r = int(rows), c = int(cols);
  if (r < 0 || c < 0 || std::int64_t(r) * c > 3 * 14)
    throw core::InputError(name + ": " + key + " is " + std::to_string(r) + "x" +
                           std::to_string(c) + ": too large for a camera calibration");
}

// The calibration in an opened file (`name` for messages).
CameraCalibration readCalibration(cv::FileStorage& fs, const std::string& name) {
  CameraCalibration c;
  c.source = name;
  translatingOpenCvErrors(name, [&] {
    checkMatrixNode(fs["camera_matrix"], name, "camera_matrix");
    checkMatrixNode(fs["distortion_coefficients"], name, "distortion_coefficients");
    cv::Mat k, d;
    fs["camera_matrix"] >> k;
    if (k.empty()) throw core::InputError(name + ": no camera_matrix");
    if (k.rows != 3 || k.cols != 3)
      throw core::InputError(name + ": camera_matrix is " + std::to_string(k.rows) + "x" +
                             std::to_string(k.cols) + ", not 3x3");
    k.convertTo(k, CV_64F);
    c.K = cv::Matx33d(k);
    fs["distortion_coefficients"] >> d;
    if (d.empty()) throw core::InputError(name + ": no distortion_coefficients");
    d.convertTo(d, CV_64F);
    c.distortion = d.reshape(1, 1).clone();
    if (d.rows != 1 && d.cols != 1) c.distortion = d;  // validate() names the shape
    const cv::FileNode w = fs["image_width"], h = fs["image_height"];
    if (!w.empty() || !h.empty()) {
      if (w.empty() || h.empty() || !w.isInt() || !h.isInt())
        throw core::InputError(name + ": image_width and image_height must both be integers");
      c.imageSize = {int(w), int(h)};
      if (c.imageSize.width <= 0 || c.imageSize.height <= 0)
        throw core::InputError(name + ": image size " + std::to_string(c.imageSize.width) + "x" +
                               std::to_string(c.imageSize.height) + " is not valid");
    }
    const cv::FileNode e = fs["avg_reprojection_error"];
    if (!e.empty() && e.isReal()) c.rms = double(e);
  });
  c.validate();
  return c;
}

}  // namespace

CameraCalibration loadCalibration(const std::filesystem::path& path) {
  const std::string name = path.string();
  {
    std::ifstream probe(path);
    if (!probe) throw core::InputError(name + ": cannot open the calibration file");
  }
  {
    std::ifstream in(path, std::ios::binary);
    std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    checkWellFormed(text, name);
  }
  cv::FileStorage fs;
  openStorage(fs, name, cv::FileStorage::READ, name);
  return readCalibration(fs, name);
}

CameraCalibration parseCalibration(const std::string& text, const std::string& name) {
  checkWellFormed(text, name);
  cv::FileStorage fs;
  openStorage(fs, text, cv::FileStorage::READ | cv::FileStorage::MEMORY, name);
  return readCalibration(fs, name);
}

void saveCalibration(const CameraCalibration& c, const std::filesystem::path& path,
                     const std::string& comment) {
  c.validate();
  const std::string tmp = path.string() + ".part";
  cv::FileStorage fs(tmp, cv::FileStorage::WRITE | cv::FileStorage::FORMAT_YAML);
  if (!fs.isOpened()) throw std::runtime_error("cannot write " + tmp);
  if (!comment.empty()) fs << "info" << comment;
  if (c.imageSize.width > 0) {
    fs << "image_width" << c.imageSize.width;
    fs << "image_height" << c.imageSize.height;
  }
  fs << "camera_matrix" << cv::Mat(c.K);
  fs << "distortion_coefficients" << c.distortion.reshape(1, 1);
  if (c.rms >= 0) fs << "avg_reprojection_error" << c.rms;
  fs.release();
  std::error_code ec;
  std::filesystem::rename(tmp, path, ec);
  if (ec)
    throw std::runtime_error("cannot rename " + tmp + " to " + path.string() + ": " + ec.message());
}

}  // namespace ps::tracking
