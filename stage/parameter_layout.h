#pragma once
// Which coefficients describe the 21 error terms of a chain, and which of them a solver may move.
//
// Each term is absent or a polynomial of order 0..3 in its argument axis' normalised coordinate (see
// polynomial_basis.h). A coefficient is named after its term and power: xTx1, yRz0; a squareness term of
// order 0 is named plainly: xWy (higher orders: xWy0, xWy1, ...). Every coefficient is free, fixed at a value,
// or tied to a free one (value = factor * that one); dropping removes it from the model.

#include <Eigen/Core>
#include <array>
#include <string>
#include <string_view>
#include <vector>

#include "stage/axis_chain.h"
#include "stage/polynomial_basis.h"

namespace fvm::stage {

inline constexpr int kMaxOrder = 3;
inline constexpr int kMaxCoefficients = kNumErrorTerms * (kMaxOrder + 1);

struct TermSpec {
  bool present = false;
  Basis basis = Basis::kPower;
  int order = 0;
};

class ParameterLayout {
 public:
  enum class State { kFree, kFixed, kTied };
  struct Coefficient {
    std::string name;
    int term = 0;
    int power = 0;
    State state = State::kFree;
    double value = 0.0;   // kFixed: the value; kTied: the factor
    std::string tied_to;  // kTied: the free coefficient it follows
  };
  // Two or more coefficients with one effect on the forward model: `dependent` equals the sum of
  // factor * coefficient over `on` (e.g. xWy = -1 * xTy1 in the power basis).
  struct Alias {
    std::string dependent;
    std::vector<std::pair<std::string, double>> on;
    std::string Describe() const;
  };

  ParameterLayout(AxisChain chain, std::array<Travel, 3> travel);

  // Sets term `name` (VDI or ISO name) to a polynomial; its coefficients become free. Throws on a bad name/order.
  void SetTerm(std::string_view term_name, Basis basis, int order);
  void RemoveTerm(std::string_view term_name);
  void Fix(std::string_view coefficient, double value);
  // Refuses (std::invalid_argument naming both) a target that is not free, a self-tie, a coefficient that others
  // follow (ties are one level deep) and a non-finite factor.
  void Tie(std::string_view coefficient, std::string_view free_coefficient, double factor);
  void Free(std::string_view coefficient);
  void Drop(std::string_view coefficient);

  const AxisChain& chain() const { return chain_; }
  const std::array<Travel, 3>& travel() const { return travel_; }
  const TermSpec& term(int index) const { return terms_[static_cast<size_t>(index)]; }
  const std::vector<Coefficient>& coefficients() const { return coefficients_; }
  int NumFree() const { return static_cast<int>(free_index_.size()); }
  // Bit k set when axis k has a present term (its own T or R, or a squareness term it carries).
  unsigned AxesWithErrors() const { return axes_with_errors_; }
  std::vector<std::string> FreeNames() const;
  int FindCoefficient(std::string_view name) const;  // -1 when absent
  int FreeIndexOf(std::string_view name) const;      // -1 when not free
  // The free slot a coefficient (by index into coefficients()) moves with: its own, or its tie target's; -1 when
  // fixed.
  int SlotOf(size_t coefficient) const { return free_slot_[coefficient] >= 0 ? free_slot_[coefficient] : tied_slot_[coefficient]; }

  // All coefficient values from the free ones.
  template <typename T>
  void Expand(const T* free, T* all) const;
  // Values of the 21 terms at command q (zeros for absent terms) from all coefficient values.
  template <typename T>
  void TermValues(const T* all, const Eigen::Matrix<T, 3, 1>& q, T* e) const;
  // d(term values) / d(free coefficients) at q: 21 x NumFree. Constant in the coefficients, because every
  // term is linear in them; fixed coefficients contribute nothing.
  Eigen::MatrixXd TermDerivative(const Eigen::Vector3d& q) const;
  // The same, sparse: each non-fixed coefficient feeds one term (identification keeps one per observation).
  struct TermDerivativeEntry {
    int term;
    int slot;
    double value;
  };
  std::vector<TermDerivativeEntry> TermDerivativeEntries(const Eigen::Vector3d& q) const;

  // Exact linear dependencies between the free coefficients seen through the forward model at `commands`
  // (relative tolerance on column residuals), in layout order: the earlier coefficient is kept.
  std::vector<Alias> FindAliases(const std::vector<Eigen::Vector3d>& commands, const double* free_values = nullptr,
                                 double tolerance = 1e-9) const;

 private:
  int RequireCoefficient(std::string_view name) const;
  std::string FollowerOf(std::string_view coefficient) const;  // a coefficient tied to it, or empty
  void Reindex();

  AxisChain chain_;
  std::array<Travel, 3> travel_;
  std::array<TermSpec, kNumErrorTerms> terms_{};
  std::vector<Coefficient> coefficients_;  // term order, then power
  std::vector<int> free_index_;            // coefficient index of each free coefficient
  std::vector<int> free_slot_;             // free slot of each coefficient, -1 if not free
  std::vector<int> tied_slot_;             // free slot a tied coefficient follows, -1 otherwise
  unsigned axes_with_errors_ = 0;
};

// How people read a coefficient: translations in um, rotations and squareness in urad.
struct DisplayUnit {
  const char* name;
  double per_si;  // display value = SI value (mm or rad) * per_si
};
DisplayUnit UnitOf(const ParameterLayout::Coefficient& coefficient);

// Part coordinates of the commanded point q under the layout's error model with the given free values.
template <typename T>
Eigen::Matrix<T, 3, 1> Forward(const ParameterLayout& layout, const T* free, const Eigen::Matrix<T, 3, 1>& q,
                               const T* instrument_pose6 = nullptr);
Eigen::Vector3d Forward(const ParameterLayout& layout, const std::vector<double>& free, const Eigen::Vector3d& q);

// d(part coordinates) / d(21 term values) at q, optionally the value. The derivative w.r.t. the motion errors of
// the axes in `moving_axes` (bit k for axis k: the others have no error terms, so their derivatives are not
// needed): by hand for the small-angle chain (axis map by axis map), else automatic differentiation (ceres::Jet);
// then the exact linear map from terms to motions.
Eigen::Matrix<double, 3, kNumErrorTerms> TermJacobian(const AxisChain& chain, const double* e,
                                                      const Eigen::Vector3d& q, Eigen::Vector3d* value = nullptr,
                                                      unsigned moving_axes = 0b111);
// d(part coordinates) / d(free coefficients) at q: TermJacobian * TermDerivative.
Eigen::MatrixXd ForwardJacobian(const ParameterLayout& layout, const double* free, const Eigen::Vector3d& q,
                                Eigen::Vector3d* value = nullptr);

// ---- template definitions ----

template <typename T>
void ParameterLayout::Expand(const T* free, T* all) const {
  for (size_t i = 0; i < coefficients_.size(); ++i) {
    const Coefficient& c = coefficients_[i];
    switch (c.state) {
      case State::kFree: all[i] = free[free_slot_[i]]; break;
      case State::kFixed: all[i] = T(c.value); break;
      case State::kTied: all[i] = c.value * free[tied_slot_[i]]; break;
    }
  }
}

// The basis functions at a command, evaluated once per axis for the terms that share its basis (the seven terms
// of an axis usually do): a basis of lower order is a prefix of the same basis of higher order.
template <typename T>
class AxisBases {
 public:
  const T* At(const TermSpec& spec, int axis, const Travel& travel, const T& q) {
    const size_t a = static_cast<size_t>(axis);
    if (order_[a] < spec.order || basis_[a] != spec.basis) {
      EvaluateBasis(spec.basis, spec.order, NormalisedCoordinate(spec.basis, travel, q), values_[a]);
      order_[a] = spec.order;
      basis_[a] = spec.basis;
    }
    return values_[a];
  }

 private:
  T values_[3][kMaxOrder + 1];
  int order_[3] = {-1, -1, -1};
  Basis basis_[3] = {};
};

template <typename T>
void ParameterLayout::TermValues(const T* all, const Eigen::Matrix<T, 3, 1>& q, T* e) const {
  for (int t = 0; t < kNumErrorTerms; ++t) e[t] = T(0.0);
  AxisBases<T> bases;
  const T* basis = nullptr;
  int previous_term = -1;
  for (size_t i = 0; i < coefficients_.size(); ++i) {
    const Coefficient& c = coefficients_[i];
    if (c.term != previous_term) {
      const int axis = static_cast<int>(chain_.ArgumentAxis(c.term));
      basis = bases.At(terms_[static_cast<size_t>(c.term)], axis, travel_[static_cast<size_t>(axis)], q[axis]);
      previous_term = c.term;
    }
    e[c.term] += all[i] * basis[c.power];
  }
}

template <typename T>
Eigen::Matrix<T, 3, 1> Forward(const ParameterLayout& layout, const T* free, const Eigen::Matrix<T, 3, 1>& q,
                               const T* instrument_pose6) {
  std::vector<T> all(layout.coefficients().size());
  layout.Expand(free, all.data());
  T e[kNumErrorTerms];
  layout.TermValues(all.data(), q, e);
  return ChainForward(layout.chain(), e, q, instrument_pose6);
}

}  // namespace fvm::stage
