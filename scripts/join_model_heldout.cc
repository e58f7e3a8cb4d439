// SPDX-License-Identifier: Apache-2.0
// An experiment, not part of the build (docs/reconstruction.md section 6,
// "Joins: the oracle's bound and a nonlinear classifier (s21)"): join models
// compared on the labelled joins that
// JoinClassifier.DISABLED_TrainOnSimulatedStops writes with
// VB_JOIN_DUMP=joins.csv. Trains on seeds 1000-1079 and holds out 1080-1099:
// the committed weights (copied below), the same logistic model retrained, and
// a quadratic expansion (standardised features, all products), each with L2 1,
// 10, 100, per model (joins to a cane, to the trunk or head).
//   g++ -O2 -std=c++17 -I/usr/include/eigen3 scripts/join_model_heldout.cc -o
//   heldout
//   ./heldout joins.csv            (held-out AUC and log-loss)
//   ./heldout joins.csv -1 1 w.txt (the quadratic model, L2 1, on every seed,
//   written to w.txt)
#include <cstdio>
#include <vector>

#include "logistic_fit.h"
const double kCane[22] = {-1.0182, -0.0559, -1.5357, 0.0000,  0.0000, 0.5341, 0.5073,  -0.4121,
                          0.4987,  -0.6448, 0.1947,  -0.1707, 1.9917, 1.7472, -0.0651, -0.4369,
                          -1.5173, 0,       0,       0,       0,      0};
const double kRoot[22] = {0.1569, -0.1006, -0.1176, -0.3721, 0.3721, 0.0000,  0.3781, 0.0000,
                          0.0000, 0.1190,  0.1167,  0.0000,  2.6093, -0.7673, 0.1016, 0.0254,
                          1.0847, 0,       0,       0,       0,      0};
int main(int argc, char **argv) {
  const int img_only = argc > 2 ? std::atoi(argv[2]) : -1;
  std::vector<Ex> all;
  for (Ex &e : ReadExamples(argv[1], 22)) {
    for (int k = 17; k < 22; ++k) e.f[k] = 0;  // the committed model does not use them
    if (img_only < 0 || e.img == img_only) all.push_back(e);
  }
  if (argc > 3) {  // export: train on every seed, quadratic, l2 = argv[3]
    FILE *out = std::fopen(argv[4], "w");
    for (int root = 0; root < 2; ++root) {
      std::vector<const Ex *> tr;
      for (auto &e : all)
        if ((e.f[3] != 0 || e.f[4] != 0) == (root == 1)) tr.push_back(&e);
      std::vector<int> use;
      for (int k = 1; k <= 16; ++k)
        if (root ? (k != 5 && k != 7 && k != 8 && k != 11 && k != 4) : (k != 3 && k != 4))
          use.push_back(k);
      Expander ex{use, {}, {}, true};
      ex.Fit(tr);
      Eigen::VectorXd w = Train(tr, ex, std::atof(argv[3]));
      std::fprintf(out, "%zu", use.size());
      for (size_t k = 0; k < use.size(); ++k)
        std::fprintf(out, " %d %.9g %.9g", use[k], ex.mu[k], ex.sd[k]);
      std::fprintf(out, "\n%d", (int)w.size());
      for (int k = 0; k < w.size(); ++k) std::fprintf(out, " %.9g", w(k));
      std::fprintf(out, "\n");
    }
    std::fclose(out);
    return 0;
  }
  std::vector<std::pair<double, int>> all_committed;
  std::vector<std::vector<std::pair<double, int>>> all_models(7);
  for (int root = 0; root < 2; ++root) {
    std::vector<const Ex *> tr, te;
    for (auto &e : all) {
      const bool is_root = e.f[3] != 0 || e.f[4] != 0;
      if (is_root != (root == 1)) continue;
      (e.seed < 1080 ? tr : te).push_back(&e);
    }
    int pos_tr = 0, pos_te = 0;
    for (auto *e : tr) pos_tr += e->y;
    for (auto *e : te) pos_te += e->y;
    std::printf("%s: train %zu (%d right), held out %zu (%d right)\n", root ? "root" : "cane",
                tr.size(), pos_tr, te.size(), pos_te);
    std::vector<std::pair<double, int>> committed;
    for (auto *e : te) {
      double z = 0;
      for (int k = 0; k < 22; ++k) z += e->f[k] * (root ? kRoot[k] : kCane[k]);
      committed.push_back({1 / (1 + std::exp(-z)), e->y});
    }
    all_committed.insert(all_committed.end(), committed.begin(), committed.end());
    std::printf("  committed weights: AUC %.4f log-loss %.4f\n", Auc(committed),
                LogLoss(committed));
    std::vector<int> use;
    for (int k = 1; k <= 16; ++k)
      if (root ? (k != 5 && k != 7 && k != 8 && k != 11 && k != 4) : (k != 3 && k != 4))
        use.push_back(k);
    int m = 0;
    for (bool quad : {false, true})
      for (double l2 : {1.0, 10.0, 100.0}) {
        Expander ex{use, {}, {}, quad};
        ex.Fit(tr);
        Eigen::VectorXd w = Train(tr, ex, l2);
        std::vector<std::pair<double, int>> s;
        for (auto *e : te) {
          double z = std::clamp(ex.Map(*e).dot(w), -30.0, 30.0);
          s.push_back({1 / (1 + std::exp(-z)), e->y});
        }
        all_models[m].insert(all_models[m].end(), s.begin(), s.end());
        ++m;
        std::printf("  %s l2 %g (%d weights): AUC %.4f log-loss %.4f\n",
                    quad ? "quadratic" : "linear", l2, (int)w.size(), Auc(s), LogLoss(s));
      }
  }
  std::printf("both models pooled: committed AUC %.4f log-loss %.4f\n", Auc(all_committed),
              LogLoss(all_committed));
  int m = 0;
  for (bool quad : {false, true})
    for (double l2 : {1.0, 10.0, 100.0})
      std::printf("  %s l2 %g: AUC %.4f log-loss %.4f\n", quad ? "quadratic" : "linear", l2,
                  Auc(all_models[m]), LogLoss(all_models[m])),
          ++m;
}
