// The Levenberg-Marquardt loop on small normal equations (fitting/levenberg_marquardt.hpp) that the
// FOPDT fit and the axis fit run: the residuals kept for the end point, and the confirming trials
// costed by the residuals alone.
#include <catch2/catch.hpp>

#include <cmath>
#include <vector>

#include <Eigen/Dense>

#include "tunekit/fitting/levenberg_marquardt.hpp"

using namespace tunekit::fitting;

namespace {

// y = a exp(-b t) on 200 samples, a = 2, b = 0.7, with a deterministic ripple as noise.
struct Decay {
  std::vector<double> t, y;
  int equations = 0, costs = 0;
  Decay() {
    for (int i = 0; i < 200; ++i) {
      t.push_back(0.05 * i);
      y.push_back(2.0 * std::exp(-0.7 * t.back()) + 0.01 * std::sin(1.3 * i));
    }
  }
  double cost(std::span<const double> p) {
    ++costs;
    double c = 0;
    for (std::size_t i = 0; i < t.size(); ++i) {
      const double r = p[0] * std::exp(-p[1] * t[i]) - y[i];
      c += r * r;
    }
    return c;
  }
  double equations_at(std::span<const double> p, Eigen::Matrix2d& N, Eigen::Vector2d& g, std::span<double> res) {
    ++equations;
    N.setZero();
    g.setZero();
    double c = 0;
    for (std::size_t i = 0; i < t.size(); ++i) {
      const double e = std::exp(-p[1] * t[i]);
      const Eigen::Vector2d j(e, -p[0] * t[i] * e);
      const double r = p[0] * e - y[i];
      if (!res.empty()) res[i] = r;
      N += j * j.transpose();
      g += j * r;
      c += r * r;
    }
    return c;
  }
};

}  // namespace

TEST_CASE("ResidualMemo: the residuals of the end point, whichever of the two kept evaluations it is") {
  lm_detail::ResidualMemo memo(3);
  auto evaluate = [&memo](std::vector<double> q, double c) {
    auto out = memo.trial();
    for (std::size_t i = 0; i < out.size(); ++i) out[i] = q[0] + static_cast<double>(i);
    memo.evaluated(q, c);
  };
  evaluate({1}, 5.0);  // the best so far
  evaluate({2}, 3.0);  // better: 1 is now the other kept evaluation
  evaluate({3}, 4.0);  // worse: written over 1's residuals
  const std::vector<double> p3{3};
  const std::vector<double> p1{1};
  lm_detail::ResidualMemo copy = memo;
  CHECK(copy.take(p1).empty());  // overwritten, so not claimed
  CHECK(copy.take(p3) == std::vector<double>{3, 4, 5});
  const std::vector<double> p2{2};
  CHECK(memo.take(p2) == std::vector<double>{2, 3, 4});
}

TEST_CASE("confirm with trials costed first: the same end point, no normal equations for the last trial") {
  const std::vector<double> lo{-10, 0}, hi{10, 10};
  const std::vector<char> fixed(2, 0);
  auto solve = [&](bool cost_first, Decay& d, std::vector<double>& p) {
    lm_detail::ResidualMemo memo(d.t.size());
    auto equations = [&](std::span<const double> q, Eigen::Matrix2d& N, Eigen::Vector2d& g) {
      const double c = d.equations_at(q, N, g, memo.trial());
      memo.evaluated(q, c);
      return c;
    };
    lm_detail::Equations<Eigen::Matrix2d, Eigen::Vector2d> at;
    at.cost = equations(p, at.N, at.g);
    double lambda = lm_detail::kInitialDamping;
    lm_detail::polish_from(std::span<double>(p), lo, hi, fixed, equations, at, lambda, true);
    const lm_detail::Tolerances tol;
    const auto c = cost_first ? lm_detail::confirm(std::span<double>(p), lo, hi, fixed, equations, at, lambda, tol,
                                                   [&d](std::span<const double> q) { return d.cost(q); })
                              : lm_detail::confirm(std::span<double>(p), lo, hi, fixed, equations, at, lambda, tol);
    REQUIRE(c.converged());
    const std::vector<double> res = memo.take(p);
    REQUIRE(res.size() == d.t.size());
    double rss = 0;
    for (double r : res) rss += r * r;
    CHECK(rss == at.cost);  // the kept residuals are those of the end point
  };
  Decay plain, costed;
  std::vector<double> p_plain{1.5, 0.5}, p_costed{1.5, 0.5};
  solve(false, plain, p_plain);
  solve(true, costed, p_costed);
  CHECK(p_costed[0] == Approx(p_plain[0]).epsilon(1e-9));
  CHECK(p_costed[1] == Approx(p_plain[1]).epsilon(1e-9));
  CHECK(costed.costs >= 1);
  CHECK(costed.equations < plain.equations);
}
