#!/usr/bin/env bash
# Every dense decomposition of the library is built through core/dense_decomposition.h (issue 44): a matrix with
# NaN or infinity is refused there with the name of what was asked, instead of a pivoting QR indexing out of bounds.
# This test fails, naming file and line, when a library source outside that header constructs one directly: a
# decomposition type not as the template argument of Decompose<...> / DecomposeWithThreshold<...>, or one of
# Eigen's shorthand methods (m.ldlt(), m.colPivHouseholderQr(), ...). Tests and benchmarks compute reference values
# as they like and are not searched.
#
# Usage: dense_decomposition_sources_test.sh SOURCE_DIR
set -euo pipefail
root="${1:?usage: $0 SOURCE_DIR}"
cd "$root"
types='(HouseholderQR|ColPivHouseholderQR|FullPivHouseholderQR|CompleteOrthogonalDecomposition|JacobiSVD|BDCSVD|LLT|LDLT|PartialPivLU|FullPivLU|SelfAdjointEigenSolver|GeneralizedSelfAdjointEigenSolver|EigenSolver|ComplexEigenSolver|RealSchur|RealQZ)'
methods='\.(householderQr|colPivHouseholderQr|fullPivHouseholderQr|completeOrthogonalDecomposition|jacobiSvd|bdcSvd|llt|ldlt|lu|partialPivLu|fullPivLu|eigenvalues|operatorNorm)\(\)'
dirs=(core stage imaging artefacts workflows report fvm python)
existing=()
for d in "${dirs[@]}"; do [[ -d $d ]] && existing+=("$d"); done
found=$(grep -rnE --include='*.h' --include='*.cc' --include='*.cpp' \
          -e "Eigen::${types}<" -e "$methods" "${existing[@]}" |
        grep -v '^core/dense_decomposition\.' |
        # A type given to the guarded entry is its template argument: drop those occurrences, keep what is left.
        sed -E "s/(Decompose|DecomposeWithThreshold)<Eigen::${types}<//g" |
        grep -E -e "Eigen::${types}<" -e "$methods" |
        # .eigenvalues() of a decomposition already made is a getter, not a construction.
        grep -vE '(eig|eigen|directions|solver)\.eigenvalues\(\)' || true)
# A getter called on a temporary from Decompose<...>(...) spans lines; its ').eigenvalues()' is no construction either.
found=$(printf '%s\n' "$found" | grep -vE '^\S+:[0-9]+:\s*\.eigenvalues\(\)' | grep -v '^$' || true)
if [[ -n $found ]]; then
  echo "Dense decompositions constructed outside core/dense_decomposition.h; build them with"
  echo "Decompose<Eigen::...>(matrix, \"what it is asked\") so that NaN and infinity are refused by name:"
  echo "$found"
  exit 1
fi
echo "every dense decomposition of the library goes through core/dense_decomposition.h"
