// Compiled vector kernels for SUNDIALS' serial N_Vector.
//
// Debian's libsundials-nvecserial (6.4.1) is built without optimisation: its
// kernels keep every loop variable in memory (N_VWSqrSumLocal_Serial spends
// about 24 instructions per element). On the cushion rig these kernels took
// about a third of the run time, although the vectors hold 10 numbers. IDA
// reaches every vector operation through the function table of its N_Vector,
// and the vectors IDA and the linear solver clone inherit that table, so
// replacing the entries of the vectors handed to IDAInit (and of the one
// handed to IDAQuadInit, which the quadratures' history is cloned from)
// replaces them everywhere. The replacements are written from the operations' definitions
// in the SUNDIALS documentation (z = a x + b y, the weighted RMS norm, ...)
// and work on the serial vector's own data; the vector type, its memory and
// every other operation stay SUNDIALS'.
#pragma once

#include <sundials/sundials_nvector.h>

namespace pneumo {

// Replaces the arithmetic and norm operations of serial vector `v` (and of
// the vectors later cloned from it) with compiled kernels. Enables the fused
// operations (linear combinations), as N_VEnableFusedOps_Serial does.
void use_compiled_serial_ops(N_Vector v);

}  // namespace pneumo
