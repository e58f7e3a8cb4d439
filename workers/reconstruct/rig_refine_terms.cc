// SPDX-License-Identifier: Apache-2.0
#include "workers/reconstruct/rig_refine_terms.h"

#include <algorithm>
#include <cmath>
#include <optional>

#include "absl/strings/str_cat.h"

namespace vb::reconstruct::rig_refine_internal {
namespace {

// The pixels of a straight 2D line (normalised coordinates of `camera`) every ~3 px along it, in
// order, where the camera sees it: inside the image and inside the fold of the distortion.
std::vector<Eigen::Vector2d> PixelCurve(const CameraCalibration& camera, const Line2D& line) {
  const Eigen::Vector2d normal = line.line.head<2>();
  const Eigen::Vector2d origin = -line.line.z() * normal;  // the line's point nearest (0, 0)
  const Eigen::Vector2d direction(normal.y(), -normal.x());
  const double step = 3.0 / camera.camera_matrix(0, 0);
  std::vector<Eigen::Vector2d> curve;
  for (double t = -3.0; t <= 3.0; t += step) {
    const Eigen::Vector2d xy = origin + t * direction;
    const Eigen::Vector2d uv = camera.NormalisedToPixel(xy);
    if (!camera.InImage(uv) || (camera.PixelToNormalised(uv) - xy).norm() > 1e-6) continue;
    curve.push_back(uv);
  }
  return curve;
}

// Whether uv lies beside the curve rather than beyond either of its ends.
bool AlongsideCurve(const std::vector<Eigen::Vector2d>& curve, const Eigen::Vector2d& uv) {
  size_t best = 0;
  double best_d2 = 1e300, best_t = 0.0;
  for (size_t k = 0; k + 1 < curve.size(); ++k) {
    const Eigen::Vector2d d = curve[k + 1] - curve[k];
    const double t = (uv - curve[k]).dot(d) / std::max(d.squaredNorm(), 1e-12);
    const double d2 = (uv - curve[k] - std::clamp(t, 0.0, 1.0) * d).squaredNorm();
    if (d2 < best_d2) best_d2 = d2, best = k, best_t = t;
  }
  return !(best == 0 && best_t < 0.0) && !(best + 2 == curve.size() && best_t > 1.0);
}

}  // namespace

bool InsideMargin(const CameraCalibration& camera, const Eigen::Vector2d& uv) {
  return uv.x() >= kMarginPx && uv.y() >= kMarginPx &&
         uv.x() <= camera.image_width - 1 - kMarginPx &&
         uv.y() <= camera.image_height - 1 - kMarginPx;
}

RigUnknowns::RigUnknowns(const RigCalibration& rig, size_t reference)
    : reference(reference),
      rotations(rig.cameras.size(), {0.0, 0.0, 0.0}),
      intrinsics(rig.cameras.size(), {0.0, 0.0, 0.0}),
      has_prior(rig.cameras.size(), false) {
  for (const CameraCalibration& camera : rig.cameras) projectors.emplace_back(camera);
}

void RigUnknowns::AddPriors(const RigCalibration& rig, const RigRefineOptions& options,
                            ceres::Problem* problem) {
  for (size_t v = 0; v < rig.cameras.size(); ++v) {
    if (v == reference || has_prior[v]) continue;
    if (!problem->HasParameterBlock(rotations[v].data())) continue;  // the camera saw nothing
    has_prior[v] = true;
    const double focal = rig.cameras[v].camera_matrix(0, 0);
    const double half_width = 0.5 * rig.cameras[v].image_width;
    problem->AddResidualBlock(new ceres::AutoDiffCostFunction<CorrectionPrior, 6, 3, 3>(
                                  new CorrectionPrior(focal / options.correction_prior_px,
                                                      half_width / options.correction_prior_px,
                                                      1.0 / options.correction_prior_px)),
                              nullptr, rotations[v].data(), intrinsics[v].data());
    if (!options.refine_principal_point) {
      problem->SetManifold(intrinsics[v].data(), new ceres::SubsetManifold(3, {1, 2}));
    }
  }
}

void RigUnknowns::SetCamerasConstant(bool constant, ceres::Problem* problem) {
  for (size_t v = 0; v < rotations.size(); ++v) {
    if (!problem->HasParameterBlock(rotations[v].data())) continue;
    if (constant || v == reference) {
      problem->SetParameterBlockConstant(rotations[v].data());
      problem->SetParameterBlockConstant(intrinsics[v].data());
    } else {
      problem->SetParameterBlockVariable(rotations[v].data());
      problem->SetParameterBlockVariable(intrinsics[v].data());
    }
  }
}

FiducialTerms::FiducialTerms(const std::vector<View2D>& views, const RigCalibration& rig,
                             size_t reference, const RigRefineOptions& options)
    : rig_(rig) {
  if (!options.use_fiducials) return;
  suffice_ = true;
  for (size_t v = 0; v < views.size(); ++v) {
    if (v == reference) continue;
    for (const FiducialObservation& f : views[v].fiducials) terms_.push_back({v, &f});
    suffice_ = suffice_ && static_cast<int>(views[v].fiducials.size()) >=
                                    options.min_fiducials_per_camera;
  }
}

const Eigen::Vector3d& FiducialTerms::Position(const Term& term) const {
  return rig_.fiducials[static_cast<size_t>(term.observation->fiducial)].position_in_platform;
}

void FiducialTerms::AddTo(RigUnknowns* unknowns, ceres::LossFunction* loss, double inv_sd,
                          ceres::Problem* problem) {
  for (Term& term : terms_) {
    term.id = problem->AddResidualBlock(
        new ceres::AutoDiffCostFunction<FiducialCost, 2, 3, 3>(
            new FiducialCost(unknowns->projectors[term.view], Position(term),
                             term.observation->uv_px, inv_sd)),
        loss, unknowns->rotations[term.view].data(), unknowns->intrinsics[term.view].data());
  }
}

double FiducialTerms::Error(const Term& term, const RigUnknowns& unknowns) const {
  double uv[2];
  if (!ProjectCorrected(unknowns.projectors[term.view], unknowns.rotations[term.view].data(),
                        unknowns.intrinsics[term.view].data(), Position(term).data(), &uv[0],
                        &uv[1])) {
    return 1e6;
  }
  return (Eigen::Vector2d(uv[0], uv[1]) - term.observation->uv_px).norm();
}

int FiducialTerms::RejectOutliers(const RigUnknowns& unknowns, double max_px,
                                  ceres::Problem* problem, std::vector<std::string>* log) {
  const size_t before = terms_.size();
  std::erase_if(terms_, [&](const Term& term) {
    const double error = Error(term, unknowns);
    if (error <= max_px) return false;
    problem->RemoveResidualBlock(term.id);
    log->push_back(absl::StrCat(
        rig_.cameras[term.view].name, " ",
        rig_.fiducials[static_cast<size_t>(term.observation->fiducial)].name, ": detected at (",
        term.observation->uv_px.x(), ", ", term.observation->uv_px.y(), "), ", error,
        " px from where the refined rig projects it (limit ", max_px, "): rejected"));
    return true;
  });
  return static_cast<int>(before - terms_.size());
}

double FiducialTerms::RmsCorrected(const RigUnknowns& unknowns) const {
  double sum = 0.0;
  for (const Term& term : terms_) sum += std::pow(Error(term, unknowns), 2);
  return terms_.empty() ? 0.0 : std::sqrt(sum / terms_.size());
}

double FiducialTerms::RmsCalibrated() const {
  double sum = 0.0;
  for (const Term& term : terms_) {
    const std::optional<Eigen::Vector2d> uv = rig_.cameras[term.view].Project(Position(term));
    sum += uv ? (*uv - term.observation->uv_px).squaredNorm() : 1e12;
  }
  return std::sqrt(sum / std::max<size_t>(terms_.size(), 1));
}

TrellisTerms::TrellisTerms(const std::vector<TrellisLineMatch>& trellis,
                           const RigRefineOptions& options)
    : trellis_(trellis),
      options_(options),
      line_ends_(2 * trellis.size()),
      sags_(trellis.size(), 0.0) {}

int TrellisTerms::AddTo(const std::vector<View2D>& views, const RigCalibration& rig,
                        RigUnknowns* unknowns, ceres::LossFunction* loss,
                        ceres::Problem* problem) {
  int lines = 0;
  for (size_t m = 0; m < trellis_.size(); ++m) {
    const TrellisLineMatch& match = trellis_[m];
    const int axis = match.post ? 2 : 0;
    for (int k = 0, j = 0; k < 3; ++k) {
      if (k == axis) continue;
      line_ends_[2 * m][j] = match.a[k];
      line_ends_[2 * m + 1][j] = match.b[k];
      ++j;
    }
    int seen_by = 0;
    for (size_t v = 0; v < views.size(); ++v) seen_by += match.lines[v] >= 0;
    if (seen_by < 3) continue;  // two views' planes always meet: nothing to learn
    const size_t first_term = terms_.size();
    for (size_t v = 0; v < views.size(); ++v) {
      if (match.lines[v] < 0) continue;
      const CameraCalibration& camera = rig.cameras[v];
      const Line2D& line = match.post ? views[v].posts[static_cast<size_t>(match.lines[v])]
                                      : views[v].wires[static_cast<size_t>(match.lines[v])];
      curves_.push_back(line.centre_px.size() >= 2 ? line.centre_px : PixelCurve(camera, line));
      if (curves_.back().size() < 2) continue;
      for (int k = 0; k < options_.trellis_samples; ++k) {
        const double f = (k + 0.5) / options_.trellis_samples;
        const std::optional<Eigen::Vector2d> uv = camera.Project(match.a + f * (match.b - match.a));
        if (!uv || !InsideMargin(camera, *uv) || !AlongsideCurve(curves_.back(), *uv)) continue;
        auto cost = std::make_unique<TrellisLineCost>(unknowns->projectors[v], &curves_.back(),
                                                      axis, match.a[axis], match.b[axis], f,
                                                      1.0 / options_.trellis_sd_px);
        terms_.push_back({std::make_unique<TrellisLineCost>(*cost), v, m});
        problem->AddResidualBlock(
            new ceres::AutoDiffCostFunction<TrellisLineCost, 1, 3, 3, 2, 2, 1>(cost.release()),
            loss, unknowns->rotations[v].data(), unknowns->intrinsics[v].data(),
            line_ends_[2 * m].data(), line_ends_[2 * m + 1].data(), &sags_[m]);
      }
    }
    if (terms_.size() > first_term) {
      ++lines;
      const double length = std::abs(match.b[axis] - match.a[axis]);
      if (options_.trellis_direction_sd > 0 && length > 0.1) {
        problem->AddResidualBlock(
            new ceres::AutoDiffCostFunction<TrellisDirectionPrior, 2, 2, 2>(
                new TrellisDirectionPrior(1.0 / (length * options_.trellis_direction_sd))),
            nullptr, line_ends_[2 * m].data(), line_ends_[2 * m + 1].data());
      }
      if (match.post || !options_.trellis_wire_sag) problem->SetParameterBlockConstant(&sags_[m]);
    }
  }
  return lines;
}

bool TrellisTerms::SquaredErrorPx(const Term& term, const RigUnknowns& unknowns,
                                  double* d2) const {
  double r = 0.0;
  if (!(*term.cost)(unknowns.rotations[term.view].data(), unknowns.intrinsics[term.view].data(),
                    line_ends_[2 * term.match].data(), line_ends_[2 * term.match + 1].data(),
                    &sags_[term.match], &r)) {
    return false;
  }
  *d2 = r * r * options_.trellis_sd_px * options_.trellis_sd_px;
  return true;
}

int TrellisTerms::RejectMismatches(const RigUnknowns& unknowns, double max_rms_px,
                                   ceres::Problem* problem) {
  std::vector<double> sum(trellis_.size(), 0.0);
  std::vector<int> count(trellis_.size(), 0);
  for (const Term& term : terms_) {
    double d2 = 0.0;
    // Behind a camera: certainly a mismatch.
    sum[term.match] += SquaredErrorPx(term, unknowns, &d2) ? d2 : 1e6;
    ++count[term.match];
  }
  auto mismatched = [&](size_t m) {
    return count[m] > 0 && std::sqrt(sum[m] / count[m]) > max_rms_px;
  };
  int rejected = 0;
  for (size_t m = 0; m < trellis_.size(); ++m) {
    if (!mismatched(m)) continue;
    // Removing its parameter blocks removes its residuals (and its direction prior).
    problem->RemoveParameterBlock(line_ends_[2 * m].data());
    problem->RemoveParameterBlock(line_ends_[2 * m + 1].data());
    problem->RemoveParameterBlock(&sags_[m]);
    ++rejected;
  }
  std::erase_if(terms_, [&](const Term& term) { return mismatched(term.match); });
  return rejected;
}

double TrellisTerms::Rms(const RigUnknowns& unknowns) const {
  double sum = 0.0;
  int n = 0;
  for (const Term& term : terms_) {
    double d2 = 0.0;
    if (SquaredErrorPx(term, unknowns, &d2)) {
      sum += d2;
      ++n;
    }
  }
  return n > 0 ? std::sqrt(sum / n) : 0.0;
}

}  // namespace vb::reconstruct::rig_refine_internal
