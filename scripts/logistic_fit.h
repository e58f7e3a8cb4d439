// SPDX-License-Identifier: Apache-2.0
// Shared by the offline classifier experiments under scripts/ (not part of the build): AUC and
// log-loss of scored examples, a feature expansion (standardised base features, optionally all
// their products) and an L2-regularised logistic model fitted by Newton's method.
#pragma once
#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>
#include <string>
#include <utility>
#include <vector>
struct Ex {
  int seed, img, y;
  std::vector<double> f;
};
inline double Auc(std::vector<std::pair<double, int>> s) {
  std::sort(s.begin(), s.end());
  double rank = 0, pos = 0;
  for (size_t i = 0; i < s.size(); ++i)
    if (s[i].second) rank += i + 1, pos += 1;
  double neg = s.size() - pos;
  return (rank - pos * (pos + 1) / 2) / (pos * neg);
}
inline double LogLoss(const std::vector<std::pair<double, int>> &s) {
  double l = 0;
  for (auto &[p, y] : s) {
    double q = std::clamp(p, 1e-9, 1 - 1e-9);
    l -= y ? std::log(q) : std::log(1 - q);
  }
  return l / s.size();
}
// Expansion: base features (indices `use`), standardised, then all products
// i<=j if quadratic.
struct Expander {
  std::vector<int> use;
  std::vector<double> mu, sd;
  bool quad;
  void Fit(const std::vector<const Ex *> &xs) {
    mu.assign(use.size(), 0);
    sd.assign(use.size(), 0);
    for (auto *e : xs)
      for (size_t k = 0; k < use.size(); ++k) mu[k] += e->f[use[k]] / xs.size();
    for (auto *e : xs)
      for (size_t k = 0; k < use.size(); ++k)
        sd[k] += std::pow(e->f[use[k]] - mu[k], 2) / xs.size();
    for (double &v : sd) v = v > 1e-12 ? std::sqrt(v) : 1.0;
  }
  Eigen::VectorXd Map(const Ex &e) const {
    std::vector<double> z;
    for (size_t k = 0; k < use.size(); ++k) z.push_back((e.f[use[k]] - mu[k]) / sd[k]);
    std::vector<double> out = {1.0};
    out.insert(out.end(), z.begin(), z.end());
    if (quad)
      for (size_t i = 0; i < z.size(); ++i)
        for (size_t j = i; j < z.size(); ++j) out.push_back(z[i] * z[j]);
    return Eigen::Map<Eigen::VectorXd>(out.data(), out.size());
  }
};
inline Eigen::VectorXd Train(const std::vector<const Ex *> &xs, const Expander &ex, double l2) {
  const int n = ex.Map(*xs[0]).size();
  Eigen::MatrixXd X(xs.size(), n);
  Eigen::VectorXd y(xs.size());
  for (size_t i = 0; i < xs.size(); ++i) X.row(i) = ex.Map(*xs[i]), y(i) = xs[i]->y;
  Eigen::VectorXd w = Eigen::VectorXd::Zero(n);
  Eigen::VectorXd ridge = Eigen::VectorXd::Constant(n, l2);
  ridge(0) = 0;
  for (int it = 0; it < 40; ++it) {
    Eigen::VectorXd z = X * w, p(z.size());
    for (int i = 0; i < z.size(); ++i) p(i) = 1 / (1 + std::exp(-std::clamp(z(i), -30.0, 30.0)));
    Eigen::VectorXd g = X.transpose() * (p - y) + ridge.cwiseProduct(w);
    Eigen::VectorXd s = (p.array() * (1 - p.array())).matrix();
    Eigen::MatrixXd H = X.transpose() * s.asDiagonal() * X;
    H.diagonal() += ridge;
    H.diagonal().array() += 1e-9;
    Eigen::VectorXd step = H.ldlt().solve(g);
    w -= step;
    if (step.norm() < 1e-8) break;
  }
  return w;
}
// The number of features of the first row (the columns after seed, img and label).
inline size_t FeatureCount(const char *path) {
  std::ifstream in(path);
  std::string line;
  if (!std::getline(in, line)) return 0;
  size_t commas = 0;
  for (char c : line) commas += c == ',' ? 1 : 0;
  return commas >= 3 ? commas - 2 : 0;
}

// Examples from a CSV of lines "seed,img,y,f0,f1,...": those with exactly `features` features.
inline std::vector<Ex> ReadExamples(const char *path, size_t features) {
  std::ifstream in(path);
  std::string line;
  std::vector<Ex> all;
  while (std::getline(in, line)) {
    std::stringstream ss(line);
    std::string t;
    Ex e;
    std::getline(ss, t, ',');
    e.seed = std::stoi(t);
    std::getline(ss, t, ',');
    e.img = std::stoi(t);
    std::getline(ss, t, ',');
    e.y = std::stoi(t);
    while (std::getline(ss, t, ',')) e.f.push_back(std::stod(t));
    if (e.f.size() == features) all.push_back(e);
  }
  return all;
}
