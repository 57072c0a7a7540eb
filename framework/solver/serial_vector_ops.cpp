#include "framework/solver/serial_vector_ops.hpp"

#include <nvector/nvector_serial.h>

#include <algorithm>
#include <cmath>

namespace pneumo {

namespace {

// Data and length of a serial vector.
inline double* data(N_Vector v) { return NV_DATA_S(v); }
inline sunindextype length(N_Vector v) { return NV_LENGTH_S(v); }

// z = a x + b y (z may be x or y).
void linear_sum(realtype a, N_Vector x, realtype b, N_Vector y, N_Vector z) {
  const double *xd = data(x), *yd = data(y);
  double* zd = data(z);
  const sunindextype n = length(z);
  for (sunindextype i = 0; i < n; ++i) zd[i] = a * xd[i] + b * yd[i];
}

void constant(realtype c, N_Vector z) { std::fill_n(data(z), length(z), c); }

void product(N_Vector x, N_Vector y, N_Vector z) {
  const double *xd = data(x), *yd = data(y);
  double* zd = data(z);
  for (sunindextype i = 0, n = length(z); i < n; ++i) zd[i] = xd[i] * yd[i];
}

void divide(N_Vector x, N_Vector y, N_Vector z) {
  const double *xd = data(x), *yd = data(y);
  double* zd = data(z);
  for (sunindextype i = 0, n = length(z); i < n; ++i) zd[i] = xd[i] / yd[i];
}

void scale(realtype c, N_Vector x, N_Vector z) {
  const double* xd = data(x);
  double* zd = data(z);
  for (sunindextype i = 0, n = length(z); i < n; ++i) zd[i] = c * xd[i];
}

void absolute(N_Vector x, N_Vector z) {
  const double* xd = data(x);
  double* zd = data(z);
  for (sunindextype i = 0, n = length(z); i < n; ++i) zd[i] = std::abs(xd[i]);
}

void inverse(N_Vector x, N_Vector z) {
  const double* xd = data(x);
  double* zd = data(z);
  for (sunindextype i = 0, n = length(z); i < n; ++i) zd[i] = 1.0 / xd[i];
}

void add_constant(N_Vector x, realtype b, N_Vector z) {
  const double* xd = data(x);
  double* zd = data(z);
  for (sunindextype i = 0, n = length(z); i < n; ++i) zd[i] = xd[i] + b;
}

realtype max_norm(N_Vector x) {
  const double* xd = data(x);
  double m = 0.0;
  for (sunindextype i = 0, n = length(x); i < n; ++i) m = std::max(m, std::abs(xd[i]));
  return m;
}

// sum (x_i w_i)^2, over the entries with id_i > 0 if id is given.
double weighted_square_sum(N_Vector x, N_Vector w, N_Vector id) {
  const double *xd = data(x), *wd = data(w);
  const double* idd = id ? data(id) : nullptr;
  double s = 0.0;
  for (sunindextype i = 0, n = length(x); i < n; ++i) {
    if (idd && !(idd[i] > 0.0)) continue;
    const double p = xd[i] * wd[i];
    s += p * p;
  }
  return s;
}

// Weighted root-mean-square norm sqrt(sum (x_i w_i)^2 / n); the masked form
// sums over id_i > 0 only and still divides by n.
realtype wrms_norm(N_Vector x, N_Vector w) {
  return std::sqrt(weighted_square_sum(x, w, nullptr) / static_cast<double>(length(x)));
}
realtype wrms_norm_mask(N_Vector x, N_Vector w, N_Vector id) {
  return std::sqrt(weighted_square_sum(x, w, id) / static_cast<double>(length(x)));
}
realtype wsqrsum_local(N_Vector x, N_Vector w) { return weighted_square_sum(x, w, nullptr); }
realtype wsqrsum_mask_local(N_Vector x, N_Vector w, N_Vector id) { return weighted_square_sum(x, w, id); }

// z = sum_j c_j X_j (z may be one of the X_j: each entry is read before it
// is written).
int linear_combination(int nvec, realtype* c, N_Vector* X, N_Vector z) {
  double* zd = data(z);
  const sunindextype n = length(z);
  if (nvec == 1) {
    scale(c[0], X[0], z);
    return 0;
  }
  const double* x0 = data(X[0]);
  const double* x1 = data(X[1]);
  for (sunindextype i = 0; i < n; ++i) {
    double s = c[0] * x0[i] + c[1] * x1[i];
    for (int j = 2; j < nvec; ++j) s += c[j] * data(X[j])[i];
    zd[i] = s;
  }
  return 0;
}

// Z_j = a_j x + Y_j.
int scale_add_multi(int nvec, realtype* a, N_Vector x, N_Vector* Y, N_Vector* Z) {
  const double* xd = data(x);
  const sunindextype n = length(x);
  for (int j = 0; j < nvec; ++j) {
    const double* yd = data(Y[j]);
    double* zd = data(Z[j]);
    for (sunindextype i = 0; i < n; ++i) zd[i] = a[j] * xd[i] + yd[i];
  }
  return 0;
}

// Z_j = a X_j + b Y_j.
int linear_sum_array(int nvec, realtype a, N_Vector* X, realtype b, N_Vector* Y, N_Vector* Z) {
  for (int j = 0; j < nvec; ++j) linear_sum(a, X[j], b, Y[j], Z[j]);
  return 0;
}

// Z_j = c_j X_j.
int scale_array(int nvec, realtype* c, N_Vector* X, N_Vector* Z) {
  for (int j = 0; j < nvec; ++j) scale(c[j], X[j], Z[j]);
  return 0;
}

int constant_array(int nvec, realtype c, N_Vector* Z) {
  for (int j = 0; j < nvec; ++j) constant(c, Z[j]);
  return 0;
}

int wrms_norm_array(int nvec, N_Vector* X, N_Vector* W, realtype* norms) {
  for (int j = 0; j < nvec; ++j) norms[j] = wrms_norm(X[j], W[j]);
  return 0;
}

int wrms_norm_mask_array(int nvec, N_Vector* X, N_Vector* W, N_Vector id, realtype* norms) {
  for (int j = 0; j < nvec; ++j) norms[j] = wrms_norm_mask(X[j], W[j], id);
  return 0;
}

}  // namespace

void use_compiled_serial_ops(N_Vector v) {
  N_VEnableFusedOps_Serial(v, SUNTRUE);
  N_Vector_Ops ops = v->ops;
  ops->nvlinearsum = linear_sum;
  ops->nvconst = constant;
  ops->nvprod = product;
  ops->nvdiv = divide;
  ops->nvscale = scale;
  ops->nvabs = absolute;
  ops->nvinv = inverse;
  ops->nvaddconst = add_constant;
  ops->nvmaxnorm = max_norm;
  ops->nvwrmsnorm = wrms_norm;
  ops->nvwrmsnormmask = wrms_norm_mask;
  ops->nvwsqrsumlocal = wsqrsum_local;
  ops->nvwsqrsummasklocal = wsqrsum_mask_local;
  ops->nvlinearcombination = linear_combination;
  ops->nvscaleaddmulti = scale_add_multi;
  ops->nvlinearsumvectorarray = linear_sum_array;
  ops->nvscalevectorarray = scale_array;
  ops->nvconstvectorarray = constant_array;
  ops->nvwrmsnormvectorarray = wrms_norm_array;
  ops->nvwrmsnormmaskvectorarray = wrms_norm_mask_array;
}

}  // namespace pneumo
