// RAII owners for the SUNDIALS handles the solver creates.
#pragma once

#include <idas/idas.h>
#include <sundials/sundials_context.h>
#include <sundials/sundials_linearsolver.h>
#include <sundials/sundials_matrix.h>
#include <sundials/sundials_nvector.h>

#include <memory>
#include <stdexcept>

namespace pneumo {

struct ContextOwner {
  SUNContext ctx = nullptr;
  ContextOwner() {
    if (SUNContext_Create(nullptr, &ctx) != 0) throw std::runtime_error("SUNContext_Create failed");
  }
  ~ContextOwner() { SUNContext_Free(&ctx); }
  ContextOwner(const ContextOwner&) = delete;
  ContextOwner& operator=(const ContextOwner&) = delete;
};
struct VectorDeleter {
  void operator()(_generic_N_Vector* v) const { N_VDestroy(v); }
};
struct MatrixDeleter {
  void operator()(_generic_SUNMatrix* m) const { SUNMatDestroy(m); }
};
struct SolverDeleter {
  void operator()(_generic_SUNLinearSolver* s) const { SUNLinSolFree(s); }
};
struct IdaDeleter {
  void operator()(void* mem) const { IDAFree(&mem); }
};
using VectorPtr = std::unique_ptr<_generic_N_Vector, VectorDeleter>;
using MatrixPtr = std::unique_ptr<_generic_SUNMatrix, MatrixDeleter>;
using SolverPtr = std::unique_ptr<_generic_SUNLinearSolver, SolverDeleter>;
using IdaPtr = std::unique_ptr<void, IdaDeleter>;

}  // namespace pneumo
