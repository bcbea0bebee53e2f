#include "stage/parameter_layout.h"

#include "stage/linear_dependence.h"

#include <ceres/jet.h>

#include <bit>

#include <cmath>
#include <sstream>
#include <stdexcept>

namespace fvm::stage {
namespace {

int RequireTerm(std::string_view name) {
  const std::optional<int> term = FindErrorTerm(name);
  if (!term) throw std::invalid_argument("unknown error term '" + std::string(name) + "' (use VDI 2617-3 names such as xTx, yRz, xWy)");
  return *term;
}

std::string CoefficientName(int term, int power, int order) {
  const ErrorTerm& info = GetErrorTerm(term);
  std::string name(info.vdi);
  if (info.kind == ErrorKind::kSquareness && order == 0) return name;
  return name + std::to_string(power);
}

}  // namespace

std::string ParameterLayout::Alias::Describe() const {
  std::ostringstream out;
  out << dependent << " =";
  for (size_t i = 0; i < on.size(); ++i) out << (i ? " + " : " ") << on[i].second << " * " << on[i].first;
  return out.str();
}

ParameterLayout::ParameterLayout(AxisChain chain, std::array<Travel, 3> travel)
    : chain_(std::move(chain)), travel_(travel) {
  for (const Travel& t : travel_) t.Check();
}

void ParameterLayout::SetTerm(std::string_view term_name, Basis basis, int order) {
  const int term = RequireTerm(term_name);
  if (order < 0 || order > kMaxOrder) {
    throw std::invalid_argument("term " + std::string(term_name) + ": order " + std::to_string(order) + " outside 0.." +
                                std::to_string(kMaxOrder));
  }
  RemoveTerm(term_name);
  terms_[static_cast<size_t>(term)] = TermSpec{true, basis, order};
  // Keep coefficients sorted by term, then power, so TermValues evaluates each basis once.
  auto at = coefficients_.begin();
  while (at != coefficients_.end() && at->term < term) ++at;
  std::vector<Coefficient> added;
  for (int p = 0; p <= order; ++p) {
    Coefficient c;
    c.name = CoefficientName(term, p, order);
    c.term = term;
    c.power = p;
    added.push_back(c);
  }
  coefficients_.insert(at, added.begin(), added.end());
  Reindex();
}

void ParameterLayout::RemoveTerm(std::string_view term_name) {
  const int term = RequireTerm(term_name);
  for (const Coefficient& c : coefficients_) {
    if (c.state == State::kTied && GetErrorTerm(c.term).index != term &&
        coefficients_[static_cast<size_t>(FindCoefficient(c.tied_to))].term == term) {
      throw std::invalid_argument("cannot remove " + std::string(term_name) + ": " + c.name + " is tied to " + c.tied_to);
    }
  }
  std::erase_if(coefficients_, [term](const Coefficient& c) { return c.term == term; });
  terms_[static_cast<size_t>(term)] = TermSpec{};
  Reindex();
}

int ParameterLayout::FindCoefficient(std::string_view name) const {
  for (size_t i = 0; i < coefficients_.size(); ++i) {
    if (coefficients_[i].name == name) return static_cast<int>(i);
  }
  return -1;
}

int ParameterLayout::RequireCoefficient(std::string_view name) const {
  const int index = FindCoefficient(name);
  if (index < 0) {
    std::string known;
    for (const Coefficient& c : coefficients_) known += (known.empty() ? "" : " ") + c.name;
    throw std::invalid_argument("no coefficient '" + std::string(name) + "' in this layout (it has: " + known + ")");
  }
  return index;
}

int ParameterLayout::FreeIndexOf(std::string_view name) const {
  const int index = FindCoefficient(name);
  return index < 0 ? -1 : free_slot_[static_cast<size_t>(index)];
}

std::string ParameterLayout::FollowerOf(std::string_view coefficient) const {
  for (const Coefficient& other : coefficients_) {
    if (other.state == State::kTied && other.tied_to == coefficient) return other.name;
  }
  return {};
}

void ParameterLayout::Fix(std::string_view coefficient, double value) {
  Coefficient& c = coefficients_[static_cast<size_t>(RequireCoefficient(coefficient))];
  if (const std::string follower = FollowerOf(c.name); !follower.empty()) {
    throw std::invalid_argument("cannot fix " + c.name + ": " + follower + " is tied to it");
  }
  if (!std::isfinite(value)) throw std::invalid_argument("cannot fix " + c.name + " at a non-finite value");
  c.state = State::kFixed;
  c.value = value;
  c.tied_to.clear();
  Reindex();
}

void ParameterLayout::Tie(std::string_view coefficient, std::string_view free_coefficient, double factor) {
  // Ties are one level deep: a tied coefficient follows a free one, and nothing follows a tied one. Expand
  // reads a tied coefficient's value from its target's free slot, so a target that is not free (or a
  // coefficient that others follow becoming tied) would leave those slots unset.
  const std::string what = "cannot tie " + std::string(coefficient) + " to " + std::string(free_coefficient) + ": ";
  const int index = RequireCoefficient(coefficient);
  const int target = RequireCoefficient(free_coefficient);
  if (index == target) throw std::invalid_argument(what + "a coefficient cannot follow itself");
  const Coefficient& t = coefficients_[static_cast<size_t>(target)];
  if (t.state == State::kTied) {
    throw std::invalid_argument(what + t.name + " is itself tied to " + t.tied_to + " (tie both to " + t.tied_to + ")");
  }
  if (t.state != State::kFree) throw std::invalid_argument(what + t.name + " is fixed; the target must be free");
  if (const std::string follower = FollowerOf(coefficient); !follower.empty()) {
    throw std::invalid_argument(what + follower + " is tied to " + std::string(coefficient) + " (tie " + follower +
                                " to " + t.name + " instead)");
  }
  if (!std::isfinite(factor)) throw std::invalid_argument(what + "the factor is not finite");
  Coefficient& c = coefficients_[static_cast<size_t>(index)];
  c.state = State::kTied;
  c.value = factor;
  c.tied_to = t.name;
  Reindex();
}

void ParameterLayout::Free(std::string_view coefficient) {
  Coefficient& c = coefficients_[static_cast<size_t>(RequireCoefficient(coefficient))];
  c.state = State::kFree;
  c.value = 0.0;
  c.tied_to.clear();
  Reindex();
}

void ParameterLayout::Drop(std::string_view coefficient) {
  const int index = RequireCoefficient(coefficient);
  Fix(coefficient, 0.0);  // refuses when something is tied to it
  coefficients_.erase(coefficients_.begin() + index);
  Reindex();
}

void ParameterLayout::Reindex() {
  axes_with_errors_ = 0;
  for (int t = 0; t < kNumErrorTerms; ++t) {
    if (terms_[static_cast<size_t>(t)].present) axes_with_errors_ |= 1u << static_cast<int>(chain_.ArgumentAxis(t));
  }
  free_index_.clear();
  free_slot_.assign(coefficients_.size(), -1);
  tied_slot_.assign(coefficients_.size(), -1);
  for (size_t i = 0; i < coefficients_.size(); ++i) {
    if (coefficients_[i].state != State::kFree) continue;
    free_slot_[i] = static_cast<int>(free_index_.size());
    free_index_.push_back(static_cast<int>(i));
  }
  for (size_t i = 0; i < coefficients_.size(); ++i) {
    if (coefficients_[i].state == State::kTied) {
      tied_slot_[i] = free_slot_[static_cast<size_t>(RequireCoefficient(coefficients_[i].tied_to))];
      // Tie and Fix keep every target free; a slot of -1 here would make Expand write out of bounds.
      if (tied_slot_[i] < 0) throw std::logic_error(coefficients_[i].name + " follows " + coefficients_[i].tied_to + ", which is not free");
    }
  }
}

std::vector<std::string> ParameterLayout::FreeNames() const {
  std::vector<std::string> names;
  for (int i : free_index_) names.push_back(coefficients_[static_cast<size_t>(i)].name);
  return names;
}

std::vector<ParameterLayout::TermDerivativeEntry> ParameterLayout::TermDerivativeEntries(const Eigen::Vector3d& q) const {
  std::vector<TermDerivativeEntry> entries;
  entries.reserve(coefficients_.size());
  AxisBases<double> bases;
  const double* basis = nullptr;
  int evaluated_term = -1;
  for (size_t i = 0; i < coefficients_.size(); ++i) {
    const Coefficient& c = coefficients_[i];
    if (c.state == State::kFixed) continue;
    if (c.term != evaluated_term) {
      const int axis = static_cast<int>(chain_.ArgumentAxis(c.term));
      basis = bases.At(terms_[static_cast<size_t>(c.term)], axis, travel_[static_cast<size_t>(axis)], q[axis]);
      evaluated_term = c.term;
    }
    const double factor = c.state == State::kFree ? 1.0 : c.value;
    entries.push_back({c.term, SlotOf(i), factor * basis[c.power]});
  }
  return entries;
}

Eigen::MatrixXd ParameterLayout::TermDerivative(const Eigen::Vector3d& q) const {
  Eigen::MatrixXd d = Eigen::MatrixXd::Zero(kNumErrorTerms, NumFree());
  for (const TermDerivativeEntry& e : TermDerivativeEntries(q)) d(e.term, e.slot) += e.value;
  return d;
}

std::vector<ParameterLayout::Alias> ParameterLayout::FindAliases(const std::vector<Eigen::Vector3d>& commands,
                                                                 const double* free_values, double tolerance) const {
  const int n = NumFree();
  std::vector<double> zeros(static_cast<size_t>(n), 0.0);
  const double* values = free_values ? free_values : zeros.data();
  Eigen::MatrixXd j(3 * static_cast<Eigen::Index>(commands.size()), n);
  for (size_t k = 0; k < commands.size(); ++k) j.middleRows(3 * static_cast<Eigen::Index>(k), 3) = ForwardJacobian(*this, values, commands[k]);

  std::vector<int> order(static_cast<size_t>(n));
  for (int c = 0; c < n; ++c) order[static_cast<size_t>(c)] = c;
  const std::vector<std::string> names = FreeNames();
  std::vector<Alias> aliases;
  for (const ColumnDependence& d : FindDependentColumns(j, order, tolerance)) {
    Alias alias{names[static_cast<size_t>(d.column)], {}};
    for (const auto& [column, factor] : d.on) alias.on.emplace_back(names[static_cast<size_t>(column)], factor);
    aliases.push_back(std::move(alias));
  }
  return aliases;
}

DisplayUnit UnitOf(const ParameterLayout::Coefficient& coefficient) {
  if (GetErrorTerm(coefficient.term).kind == ErrorKind::kTranslation) return {"um", 1e3};
  return {"urad", 1e6};
}

Eigen::Vector3d Forward(const ParameterLayout& layout, const std::vector<double>& free, const Eigen::Vector3d& q) {
  if (static_cast<int>(free.size()) != layout.NumFree()) throw std::invalid_argument("wrong number of free coefficients");
  return Forward(layout, free.data(), q);
}

namespace {

template <int N>
Eigen::Matrix<double, 3, kMotionErrors> MotionJacobian(const AxisChain& chain, const double* motion, const Eigen::Vector3d& q,
                                                       unsigned moving_axes, Eigen::Vector3d* value) {
  using Jet = ceres::Jet<double, N>;
  Jet mj[kMotionErrors];
  int slot = 0;
  std::array<int, kMotionErrors> slot_of{};
  for (int i = 0; i < kMotionErrors; ++i) {
    const bool moving = (moving_axes >> (i / 6)) & 1u;
    slot_of[static_cast<size_t>(i)] = moving ? slot : -1;
    mj[i] = moving ? Jet(motion[i], slot++) : Jet(motion[i]);
  }
  const Eigen::Matrix<Jet, 3, 1> p = ChainForwardFromMotions(chain, mj, Eigen::Matrix<Jet, 3, 1>(q.cast<Jet>()));
  Eigen::Matrix<double, 3, kMotionErrors> j = Eigen::Matrix<double, 3, kMotionErrors>::Zero();
  for (int i = 0; i < kMotionErrors; ++i) {
    if (slot_of[static_cast<size_t>(i)] < 0) continue;
    for (int r = 0; r < 3; ++r) j(r, i) = p[r].v[slot_of[static_cast<size_t>(i)]];
  }
  if (value) *value = Eigen::Vector3d(p[0].a, p[1].a, p[2].a);
  return j;
}

// The same derivative by hand for the small-angle chain without an instrument frame. The chain is a composition of
// one map per axis, w -> T + (I + [e]x) w on the tool side and w -> (I + [e]x)^-1 (w - T) on the part side, so the
// derivative w.r.t. an axis' T and e is that of its own map, carried to the end by the derivatives (w.r.t. w) of
// the maps after it. Equal to automatic differentiation up to rounding, at a fraction of the work of 18-wide Jets.
Eigen::Matrix<double, 3, kMotionErrors> SmallAngleMotionJacobian(const AxisChain& chain, const double* motion,
                                                                 const Eigen::Vector3d& q, unsigned moving_axes) {
  struct AxisMap {
    Axis axis;
    bool tool_side;
    Eigen::Vector3d input;
  };
  std::vector<AxisMap> maps;
  maps.reserve(3);
  Eigen::Vector3d w = chain.tool_offset;
  for (auto it = chain.tool_axes.rbegin(); it != chain.tool_axes.rend(); ++it) {
    maps.push_back({*it, true, w});
    w = internal::AxisTranslation(chain, *it, motion, q) +
        internal::Rotate(RotationModel::kSmallAngle, internal::AxisRotation(*it, motion), w);
  }
  for (Axis axis : chain.part_axes) {
    maps.push_back({axis, false, w});
    w = internal::RotateInverse(RotationModel::kSmallAngle, internal::AxisRotation(axis, motion),
                                Eigen::Vector3d(w - internal::AxisTranslation(chain, axis, motion, q)));
  }
  const Eigen::Matrix3d identity = Eigen::Matrix3d::Identity();
  Eigen::Matrix<double, 3, kMotionErrors> j = Eigen::Matrix<double, 3, kMotionErrors>::Zero();
  Eigen::Matrix3d carry = identity;  // d(part coordinates) / d(the output of the map at hand)
  for (auto m = maps.rbegin(); m != maps.rend(); ++m) {
    const int k = static_cast<int>(m->axis);
    const Eigen::Vector3d e = internal::AxisRotation(m->axis, motion);
    Eigen::Matrix3d d_input, d_translation, d_rotation;
    if (m->tool_side) {  // T + w + e x w
      d_input = identity + Skew(e);
      d_translation = identity;
      d_rotation = -Skew(m->input);
    } else {  // g = (v - e x v + e (e.v)) / (1 + e.e) with v = w - T
      const Eigen::Vector3d v = m->input - internal::AxisTranslation(chain, m->axis, motion, q);
      const double scale = 1.0 / (1.0 + e.squaredNorm());
      const Eigen::Vector3d g = scale * (v - internal::Cross(e, v) + e * e.dot(v));
      d_input = scale * (identity - Skew(e) + e * e.transpose());
      d_translation = -d_input;
      d_rotation = scale * (Skew(v) + e * v.transpose() + e.dot(v) * identity) - 2.0 * scale * g * e.transpose();
    }
    if ((moving_axes >> k) & 1u) {
      j.block<3, 3>(0, 6 * k) = carry * d_translation;
      j.block<3, 3>(0, 6 * k + 3) = carry * d_rotation;
    }
    carry = carry * d_input;
  }
  return j;
}

}  // namespace

Eigen::Matrix<double, 3, kNumErrorTerms> TermJacobian(const AxisChain& chain, const double* e,
                                                      const Eigen::Vector3d& q, Eigen::Vector3d* value,
                                                      unsigned moving_axes) {
  double motion[kMotionErrors];
  MotionErrors(chain, e, q, motion);
  Eigen::Matrix<double, 3, kMotionErrors> jm;
  const int moving = std::popcount(moving_axes & 0b111u);
  if (moving > 0 && chain.rotation_model == RotationModel::kSmallAngle && !chain.instrument) {
    jm = SmallAngleMotionJacobian(chain, motion, q, moving_axes);
    if (value) *value = ChainForwardFromMotions(chain, motion, q);
  } else {
    switch (moving) {  // Jets only as wide as the moving axes need
      case 0: jm.setZero(); if (value) *value = ChainForwardFromMotions(chain, motion, q); break;
      case 1: jm = MotionJacobian<6>(chain, motion, q, moving_axes, value); break;
      case 2: jm = MotionJacobian<12>(chain, motion, q, moving_axes, value); break;
      default: jm = MotionJacobian<18>(chain, motion, q, moving_axes, value); break;
    }
  }
  // Terms -> motions is linear: T and R terms feed their own slot; a squareness term feeds -q_k times the
  // carrier's translation slot in the other axis' direction.
  Eigen::Matrix<double, 3, kNumErrorTerms> j;
  for (int k = 0; k < 3; ++k) {
    for (int c = 0; c < 3; ++c) {
      j.col(TranslationTerm(static_cast<Axis>(k), c)) = jm.col(6 * k + c);
      j.col(RotationTerm(static_cast<Axis>(k), c)) = jm.col(6 * k + 3 + c);
    }
  }
  for (int w = 0; w < 3; ++w) {
    const int k = static_cast<int>(chain.squareness_carrier[static_cast<size_t>(w)]);
    const ErrorTerm& term = GetErrorTerm(kFirstSquarenessTerm + w);
    const int other = static_cast<int>(term.axis) == k ? term.component : static_cast<int>(term.axis);
    j.col(kFirstSquarenessTerm + w) = -q[k] * jm.col(6 * k + other);
  }
  return j;
}

Eigen::MatrixXd ForwardJacobian(const ParameterLayout& layout, const double* free, const Eigen::Vector3d& q,
                                Eigen::Vector3d* value) {
  std::vector<double> all(layout.coefficients().size());
  layout.Expand(free, all.data());
  double e[kNumErrorTerms];
  layout.TermValues(all.data(), q, e);
  return TermJacobian(layout.chain(), e, q, value, layout.AxesWithErrors()) * layout.TermDerivative(q);
}

}  // namespace fvm::stage
