#include "serial_vector_ops.hpp"

#include <nvector/nvector_serial.h>

#include <algorithm>
#include <cfloat>
#include <cmath>

namespace granuflow::detail {
namespace {

inline double* D(N_Vector v) { return NV_DATA_S(v); }
inline long L(N_Vector v) { return NV_LENGTH_S(v); }

void linear_sum(double a, N_Vector x, double b, N_Vector y, N_Vector z) {
  const double *xd = D(x), *yd = D(y);
  double* zd = D(z);
  const long n = L(x);
  for (long i = 0; i < n; ++i) zd[i] = a * xd[i] + b * yd[i];
}
void constant(double c, N_Vector z) { std::fill(D(z), D(z) + L(z), c); }
void prod(N_Vector x, N_Vector y, N_Vector z) {
  const double *xd = D(x), *yd = D(y);
  double* zd = D(z);
  for (long i = 0, n = L(x); i < n; ++i) zd[i] = xd[i] * yd[i];
}
void div(N_Vector x, N_Vector y, N_Vector z) {
  const double *xd = D(x), *yd = D(y);
  double* zd = D(z);
  for (long i = 0, n = L(x); i < n; ++i) zd[i] = xd[i] / yd[i];
}
void scale(double c, N_Vector x, N_Vector z) {
  const double* xd = D(x);
  double* zd = D(z);
  for (long i = 0, n = L(x); i < n; ++i) zd[i] = c * xd[i];
}
void abs_value(N_Vector x, N_Vector z) {
  const double* xd = D(x);
  double* zd = D(z);
  for (long i = 0, n = L(x); i < n; ++i) zd[i] = std::abs(xd[i]);
}
void inv(N_Vector x, N_Vector z) {
  const double* xd = D(x);
  double* zd = D(z);
  for (long i = 0, n = L(x); i < n; ++i) zd[i] = 1.0 / xd[i];
}
void add_const(N_Vector x, double b, N_Vector z) {
  const double* xd = D(x);
  double* zd = D(z);
  for (long i = 0, n = L(x); i < n; ++i) zd[i] = xd[i] + b;
}
double dot(N_Vector x, N_Vector y) {
  const double *xd = D(x), *yd = D(y);
  double s = 0.0;
  for (long i = 0, n = L(x); i < n; ++i) s += xd[i] * yd[i];
  return s;
}
double max_norm(N_Vector x) {
  const double* xd = D(x);
  double m = 0.0;
  for (long i = 0, n = L(x); i < n; ++i) m = std::max(m, std::abs(xd[i]));
  return m;
}
double wsqr_sum(N_Vector x, N_Vector w) {
  const double *xd = D(x), *wd = D(w);
  double s = 0.0;
  for (long i = 0, n = L(x); i < n; ++i) {
    const double p = xd[i] * wd[i];
    s += p * p;
  }
  return s;
}
double wsqr_sum_mask(N_Vector x, N_Vector w, N_Vector id) {
  const double *xd = D(x), *wd = D(w), *idd = D(id);
  double s = 0.0;
  for (long i = 0, n = L(x); i < n; ++i)
    if (idd[i] > 0.0) {
      const double p = xd[i] * wd[i];
      s += p * p;
    }
  return s;
}
double wrms_norm(N_Vector x, N_Vector w) { return std::sqrt(wsqr_sum(x, w) / double(L(x))); }
double wrms_norm_mask(N_Vector x, N_Vector w, N_Vector id) { return std::sqrt(wsqr_sum_mask(x, w, id) / double(L(x))); }
double min_value(N_Vector x) {
  const double* xd = D(x);
  double m = xd[0];
  for (long i = 1, n = L(x); i < n; ++i) m = std::min(m, xd[i]);
  return m;
}
double wl2_norm(N_Vector x, N_Vector w) { return std::sqrt(wsqr_sum(x, w)); }
double l1_norm(N_Vector x) {
  const double* xd = D(x);
  double s = 0.0;
  for (long i = 0, n = L(x); i < n; ++i) s += std::abs(xd[i]);
  return s;
}
void compare(double c, N_Vector x, N_Vector z) {
  const double* xd = D(x);
  double* zd = D(z);
  for (long i = 0, n = L(x); i < n; ++i) zd[i] = std::abs(xd[i]) >= c ? 1.0 : 0.0;
}
// z = 1 / x where x != 0; false if some x is 0.
booleantype inv_test(N_Vector x, N_Vector z) {
  const double* xd = D(x);
  double* zd = D(z);
  bool ok = true;
  for (long i = 0, n = L(x); i < n; ++i) {
    if (xd[i] == 0.0)
      ok = false;
    else
      zd[i] = 1.0 / xd[i];
  }
  return ok ? SUNTRUE : SUNFALSE;
}
// m_i = 1 where x_i breaks constraint c_i (2: > 0, 1: >= 0, -1: <= 0, -2: < 0, 0: none), else 0; true if none does.
booleantype constr_mask(N_Vector c, N_Vector x, N_Vector m) {
  const double *cd = D(c), *xd = D(x);
  double* md = D(m);
  bool ok = true;
  for (long i = 0, n = L(x); i < n; ++i) {
    md[i] = 0.0;
    if (cd[i] == 0.0) continue;
    const bool broken =
        (std::abs(cd[i]) > 1.5 && xd[i] * cd[i] <= 0.0) || (std::abs(cd[i]) > 0.5 && xd[i] * cd[i] < 0.0);
    if (broken) md[i] = 1.0, ok = false;
  }
  return ok ? SUNTRUE : SUNFALSE;
}
double min_quotient(N_Vector num, N_Vector denom) {
  const double *nd = D(num), *dd = D(denom);
  double m = DBL_MAX;
  for (long i = 0, n = L(num); i < n; ++i)
    if (dd[i] != 0.0) m = std::min(m, nd[i] / dd[i]);
  return m;
}

// z = sum_i c_i X_i. One pass per vector when z is none of X_1.. (z may be X_0); otherwise element by element.
int linear_combination(int nvec, double* c, N_Vector* X, N_Vector z) {
  if (nvec < 1) return -1;
  const long n = L(z);
  double* zd = D(z);
  bool aliased = false;
  for (int k = 1; k < nvec; ++k) aliased |= X[k] == z;
  if (aliased) {
    for (long i = 0; i < n; ++i) {
      double s = 0.0;
      for (int k = 0; k < nvec; ++k) s += c[k] * D(X[k])[i];
      zd[i] = s;
    }
    return 0;
  }
  const double* x0 = D(X[0]);
  for (long i = 0; i < n; ++i) zd[i] = c[0] * x0[i];
  for (int k = 1; k < nvec; ++k) {
    const double* xk = D(X[k]);
    const double ck = c[k];
    for (long i = 0; i < n; ++i) zd[i] += ck * xk[i];
  }
  return 0;
}
// Z_k = a_k x + Y_k.
int scale_add_multi(int nvec, double* a, N_Vector x, N_Vector* Y, N_Vector* Z) {
  if (nvec < 1) return -1;
  const double* xd = D(x);
  const long n = L(x);
  for (int k = 0; k < nvec; ++k) {
    const double* yd = D(Y[k]);
    double* zd = D(Z[k]);
    const double ak = a[k];
    for (long i = 0; i < n; ++i) zd[i] = ak * xd[i] + yd[i];
  }
  return 0;
}
int dot_prod_multi(int nvec, N_Vector x, N_Vector* Y, double* d) {
  if (nvec < 1) return -1;
  for (int k = 0; k < nvec; ++k) d[k] = dot(x, Y[k]);
  return 0;
}
int linear_sum_array(int nvec, double a, N_Vector* X, double b, N_Vector* Y, N_Vector* Z) {
  if (nvec < 1) return -1;
  for (int k = 0; k < nvec; ++k) linear_sum(a, X[k], b, Y[k], Z[k]);
  return 0;
}
int scale_array(int nvec, double* c, N_Vector* X, N_Vector* Z) {
  if (nvec < 1) return -1;
  for (int k = 0; k < nvec; ++k) scale(c[k], X[k], Z[k]);
  return 0;
}
int const_array(int nvec, double c, N_Vector* Z) {
  if (nvec < 1) return -1;
  for (int k = 0; k < nvec; ++k) constant(c, Z[k]);
  return 0;
}
int wrms_norm_array(int nvec, N_Vector* X, N_Vector* W, double* nrm) {
  if (nvec < 1) return -1;
  for (int k = 0; k < nvec; ++k) nrm[k] = wrms_norm(X[k], W[k]);
  return 0;
}
int wrms_norm_mask_array(int nvec, N_Vector* X, N_Vector* W, N_Vector id, double* nrm) {
  if (nvec < 1) return -1;
  for (int k = 0; k < nvec; ++k) nrm[k] = wrms_norm_mask(X[k], W[k], id);
  return 0;
}

}  // namespace

void install_serial_vector_ops(N_Vector v) {
  N_VEnableFusedOps_Serial(v, SUNTRUE);
  N_Vector_Ops o = v->ops;
  o->nvlinearsum = linear_sum;
  o->nvconst = constant;
  o->nvprod = prod;
  o->nvdiv = div;
  o->nvscale = scale;
  o->nvabs = abs_value;
  o->nvinv = inv;
  o->nvaddconst = add_const;
  o->nvdotprod = dot;
  o->nvmaxnorm = max_norm;
  o->nvwrmsnorm = wrms_norm;
  o->nvwrmsnormmask = wrms_norm_mask;
  o->nvmin = min_value;
  o->nvwl2norm = wl2_norm;
  o->nvl1norm = l1_norm;
  o->nvcompare = compare;
  o->nvinvtest = inv_test;
  o->nvconstrmask = constr_mask;
  o->nvminquotient = min_quotient;
  o->nvlinearcombination = linear_combination;
  o->nvscaleaddmulti = scale_add_multi;
  o->nvdotprodmulti = dot_prod_multi;
  o->nvlinearsumvectorarray = linear_sum_array;
  o->nvscalevectorarray = scale_array;
  o->nvconstvectorarray = const_array;
  o->nvwrmsnormvectorarray = wrms_norm_array;
  o->nvwrmsnormmaskvectorarray = wrms_norm_mask_array;
  o->nvdotprodlocal = dot;
  o->nvmaxnormlocal = max_norm;
  o->nvminlocal = min_value;
  o->nvl1normlocal = l1_norm;
  o->nvinvtestlocal = inv_test;
  o->nvconstrmasklocal = constr_mask;
  o->nvminquotientlocal = min_quotient;
  o->nvwsqrsumlocal = wsqr_sum;
  o->nvwsqrsummasklocal = wsqr_sum_mask;
}

}  // namespace granuflow::detail
