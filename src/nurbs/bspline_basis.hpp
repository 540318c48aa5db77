// B-spline basis functions (Piegl & Tiller A2.1–A2.3).
//
// Notation: knot vector U of m + 1 knots, degree p, n = m − p control points; the span i
// holds u when U[i] <= u < U[i+1], and only N_{i−p..i},p are non-zero there.
#pragma once

#include <vector>

namespace nonplanar::nurbs {

/// Span index i with U[i] <= u < U[i+1], for p <= i < n; u = U[n] gives n − 1.
int find_span(int n, int p, double u, const std::vector<double>& U);

/// The p + 1 non-zero basis values N_{i−p..i},p(u) into N (size p + 1).
void basis_funs(int i, double u, int p, const std::vector<double>& U, double* N);

/// Basis values and derivatives up to order d: ders[k][j] = d^k N_{i−p+j},p / du^k,
/// ders sized (d + 1) × (p + 1), row-major.
void ders_basis_funs(int i, double u, int p, int d, const std::vector<double>& U, double* ders);

}  // namespace nonplanar::nurbs
