#include "estimator/model_file_fitness.h"

#include <string>

namespace irdist::model_file {
namespace {

const char* const kPoseKeys[] = {"slide_mm", "pan_deg",       "tilt_deg", "bias_ma",
                                 "chi2",     "channels",      "scatter_ratio",
                                 "channel",  "residual_percent"};

void EmitPose(YAML::Emitter& out, const PoseFitness& p) {
  out << YAML::Flow << YAML::BeginMap;
  out << YAML::Key << "slide_mm" << YAML::Value << p.pose.slide_mm;
  out << YAML::Key << "pan_deg" << YAML::Value << p.pose.pan_deg;
  out << YAML::Key << "tilt_deg" << YAML::Value << p.pose.tilt_deg;
  out << YAML::Key << "bias_ma" << YAML::Value << p.pose.bias_ma;
  out << YAML::Key << "chi2" << YAML::Value << p.chi2;
  out << YAML::Key << "channels" << YAML::Value << p.channels;
  out << YAML::Key << "scatter_ratio" << YAML::Value << p.scatter_ratio;
  out << YAML::Key << "channel" << YAML::Value << p.worst_channel;
  out << YAML::Key << "residual_percent" << YAML::Value << p.worst_residual_percent;
  out << YAML::EndMap;
}

PoseFitness ReadPose(const Reader& rd, const YAML::Node& n, const std::string& key) {
  rd.Keys(n, key, {std::begin(kPoseKeys), std::end(kPoseKeys)});
  PoseFitness p;
  p.pose.slide_mm = rd.Scalar<double>(n, key, "slide_mm");
  p.pose.pan_deg = rd.Scalar<double>(n, key, "pan_deg");
  p.pose.tilt_deg = rd.Scalar<double>(n, key, "tilt_deg");
  p.pose.bias_ma = rd.Scalar<double>(n, key, "bias_ma");
  p.chi2 = rd.Scalar<double>(n, key, "chi2");
  p.channels = rd.Scalar<int>(n, key, "channels");
  p.scatter_ratio = rd.Scalar<double>(n, key, "scatter_ratio");
  p.worst_channel = rd.Scalar<std::string>(n, key, "channel");
  p.worst_residual_percent = rd.Scalar<double>(n, key, "residual_percent");
  return p;
}

}  // namespace

void EmitFitness(YAML::Emitter& out, const CalibrationFitness& f) {
  if (!f.assessed) return;
  out << YAML::Key << "fitness" << YAML::Value << YAML::BeginMap;
  out << YAML::Key << "passed" << YAML::Value << f.passed;
  out << YAML::Key << "reduced_chi2" << YAML::Value << f.reduced_chi2;
  out << YAML::Key << "dof" << YAML::Value << f.dof;
  out << YAML::Key << "limit" << YAML::Value << f.limit;
  out << YAML::Key << "pose_limit" << YAML::Value << f.pose_limit;
  out << YAML::Key << "tail_probability" << YAML::Value << f.tail_probability;
  out << YAML::Key << "size_floor" << YAML::Value << f.size_floor;
  out << YAML::Key << "difference_floor" << YAML::Value << f.difference_floor;
  out << YAML::Key << "poses" << YAML::Value << f.poses;
  out << YAML::Key << "poses_over" << YAML::Value << f.poses_over;
  out << YAML::Key << "cause" << YAML::Value << YAML::DoubleQuoted << f.cause;
  out << YAML::Key << "worst_poses" << YAML::Value << YAML::BeginSeq;
  for (const PoseFitness& p : f.worst) EmitPose(out, p);
  out << YAML::EndSeq << YAML::EndMap;
}

CalibrationFitness ReadFitness(const Reader& rd, const YAML::Node& root) {
  CalibrationFitness f;
  const YAML::Node n = root["fitness"];
  if (!n.IsDefined() || n.IsNull()) return f;
  const std::string k = "fitness";
  rd.Keys(n, k, {"passed", "reduced_chi2", "dof", "limit", "pose_limit", "tail_probability",
                 "size_floor", "difference_floor", "poses", "poses_over", "cause", "worst_poses"});
  f.assessed = true;
  f.passed = rd.Scalar<bool>(n, k, "passed");
  f.reduced_chi2 = rd.Scalar<double>(n, k, "reduced_chi2");
  f.dof = rd.Scalar<int>(n, k, "dof");
  f.limit = rd.Scalar<double>(n, k, "limit");
  f.pose_limit = rd.Scalar<double>(n, k, "pose_limit");
  f.tail_probability = rd.Scalar<double>(n, k, "tail_probability");
  f.size_floor = rd.Scalar<double>(n, k, "size_floor");
  f.difference_floor = rd.Scalar<double>(n, k, "difference_floor");
  f.poses = rd.Scalar<int>(n, k, "poses");
  f.poses_over = rd.Scalar<int>(n, k, "poses_over");
  f.cause = rd.Scalar<std::string>(n, k, "cause");
  f.chi2 = f.reduced_chi2 * f.dof;
  const YAML::Node worst = rd.Child(n, k, "worst_poses");
  if (!worst.IsSequence()) rd.Fail(worst, k + ".worst_poses", "expected a sequence");
  for (size_t i = 0; i < worst.size(); ++i) {
    f.worst.push_back(ReadPose(rd, worst[i], k + ".worst_poses[" + std::to_string(i) + "]"));
  }
  return f;
}

}  // namespace irdist::model_file
