// SPDX-License-Identifier: Apache-2.0
// An experiment, not part of the build (docs/reconstruction.md section 3, "A quadratic match
// classifier (s25)"): multi-view match models compared on the labelled candidates that
// MatchClassifier.DISABLED_TrainOnSimulatedStops writes with VB_MATCH_DUMP=match.csv. Trains on
// seeds 1000-1079 and holds out 1080-1099: the committed weights (copied below), the same
// logistic model retrained, and a quadratic expansion (standardised features 1 to the last, all
// their products) with L2 1, 10, 100; with more than 22 features (a dump with features added,
// as on branch s26-width), also the quadratic model on features 1-21 alone, as committed in
// session 25. For each: AUC and log-loss, and at the selection threshold 1 / (1 + 4.5) the share
// of right candidates above it and the wrong ones above it per right one.
//   g++ -O2 -std=c++17 -I/usr/include/eigen3 scripts/match_model_heldout.cc -o heldout
//   ./heldout match.csv [img]          (held-out figures on img 0 labels, 1 images, -1 both;
//                                       trained on both inputs, as the committed weights)
//   ./heldout match.csv -1 L2 w.txt    (the quadratic model on every seed, written to w.txt:
//                                       the base features' index, mean, sd; then the weights)
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "logistic_fit.h"

namespace {

// DefaultMatchClassifier().multi_view as committed in session 22 (match_classifier.cc).
const double kCommitted[22] = {-2.3742, -0.2758, -0.2329, 0.1134,  -0.0223, -8.1053,
                               -0.2816, -1.2012, 3.7284,  1.0856,  0.8379,  -6.5119,
                               5.7752,  -7.4007, 0.2930,  -1.4455, -0.4452, 1.6496,
                               -16.7099, 1.1531, -2.6993, -2.5107};
constexpr double kThreshold = 1.0 / (1.0 + 4.5);

void Print(const char *name, const std::vector<std::pair<double, int>> &s) {
  double right = 0, right_above = 0, wrong_above = 0;
  for (const auto &[p, y] : s) {
    right += y;
    if (p > kThreshold) (y ? right_above : wrong_above) += 1;
  }
  std::printf("  %-28s AUC %.4f log-loss %.4f  right above %.4f  wrong per right above %.4f\n",
              name, Auc(s), LogLoss(s), right_above / std::max(1.0, right),
              wrong_above / std::max(1.0, right_above));
}

}  // namespace

int main(int argc, char **argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: heldout match.csv [img] [L2 out.txt]\n");
    return 2;
  }
  const int img_only = argc > 2 ? std::atoi(argv[2]) : -1;
  const size_t count = FeatureCount(argv[1]);
  const std::vector<Ex> all = ReadExamples(argv[1], count);
  std::vector<int> use, use21;
  for (int k = 1; k < static_cast<int>(count); ++k) use.push_back(k);
  for (int k = 1; k < 22; ++k) use21.push_back(k);
  if (argc > 4) {  // export: quadratic, every seed
    std::vector<const Ex *> tr;
    for (const Ex &e : all) tr.push_back(&e);
    Expander ex{use, {}, {}, true};
    ex.Fit(tr);
    const Eigen::VectorXd w = Train(tr, ex, std::atof(argv[3]));
    FILE *out = std::fopen(argv[4], "w");
    if (out == nullptr) return 1;
    std::fprintf(out, "%zu", use.size());
    for (size_t k = 0; k < use.size(); ++k)
      std::fprintf(out, " %d %.9g %.9g", use[k], ex.mu[k], ex.sd[k]);
    std::fprintf(out, "\n%d", static_cast<int>(w.size()));
    for (int k = 0; k < w.size(); ++k) std::fprintf(out, " %.9g", w(k));
    std::fprintf(out, "\n");
    std::fclose(out);
    return 0;
  }
  std::vector<const Ex *> tr, te;
  for (const Ex &e : all) {
    if (e.seed < 1080) tr.push_back(&e);
    else if (img_only < 0 || e.img == img_only) te.push_back(&e);
  }
  int right_tr = 0, right_te = 0;
  for (const Ex *e : tr) right_tr += e->y;
  for (const Ex *e : te) right_te += e->y;
  std::printf("train %zu (%d right), held out %zu (%d right)\n", tr.size(), right_tr, te.size(),
              right_te);
  std::vector<std::pair<double, int>> committed;
  for (const Ex *e : te) {
    double z = 0;
    for (int k = 0; k < 22; ++k) z += e->f[k] * kCommitted[k];
    committed.push_back({1 / (1 + std::exp(-std::clamp(z, -30.0, 30.0))), e->y});
  }
  Print("committed weights", committed);
  for (int arm : {0, 1, 2})
    for (double l2 : {1.0, 10.0, 100.0}) {
      if (arm == 2 && count <= 22) break;
      const bool quad = arm > 0;
      Expander ex{arm == 2 ? use21 : use, {}, {}, quad};
      ex.Fit(tr);
      const Eigen::VectorXd w = Train(tr, ex, l2);
      std::vector<std::pair<double, int>> s;
      for (const Ex *e : te) {
        const double z = std::clamp(ex.Map(*e).dot(w), -30.0, 30.0);
        s.push_back({1 / (1 + std::exp(-z)), e->y});
      }
      const std::string kind = arm == 2 ? "quadratic 1-21" : quad ? "quadratic" : "linear";
      const std::string name = kind + " l2 " +
                               std::to_string(static_cast<int>(l2)) + " (" +
                               std::to_string(w.size()) + ")";
      Print(name.c_str(), s);
    }
}
