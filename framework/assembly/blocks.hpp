// Equation blocks: the unit the assembly evaluates. Each component owns a
// contiguous block of residual rows and reads its local variables through an
// index map (gather); the framework adds node blocks (flow balances, stream
// mixing, kinematics, defaults of unconnected inputs). Nothing advances a
// shared offset at run time.
#pragma once

#include <map>
#include <memory>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "framework/model/circuit.hpp"

namespace pneumo {

struct EvalContext {
  const GasModel* gas = nullptr;
  const double* modes = nullptr;  // all discrete modes of the system
  bool* invalid = nullptr;
  // The conductance of the rest-heat rows (make_rest_heat_block).
  double rest_heat = 0.0;
};

// One block of residual rows over a gathered set of variables.
class Block {
 public:
  virtual ~Block() = default;
  virtual void residual(double t, const double* y, const double* yp, double* r, const EvalContext& c) const = 0;
  virtual void residual(double t, const Dual* y, const Dual* yp, Dual* r, const EvalContext& c) const = 0;
  virtual void residual(double t, const Pattern* y, const Pattern* yp, Pattern* r, const EvalContext& c) const = 0;

  std::string label;             // for diagnostics
  SourceLocation where;          // of the component / connection
  std::vector<int> vars;         // local -> global variable index
  std::vector<std::string> row_names;
  int row0 = 0;
  int n_rows = 0;
  const Component* component = nullptr;  // null for framework node blocks
  int component_index = -1;
  int mode0 = 0;
  int root0 = 0;
  std::unique_ptr<bool[]> connected;
  std::vector<int> jac_pos;      // (local row * n_local + local var) -> CSC position or -1
  // After alias elimination local i is scale[i] * y[vars[i]], or the
  // constant offset[i] when vars[i] == -1.
  std::vector<double> scale, offset;
  // The same, compiled for gather(): locals read from an unknown, constants.
  struct Mapped {
    int local, var;
    double scale;
  };
  std::vector<Mapped> mapped;
  std::vector<std::pair<int, double>> constants;
  // AD directions: one per distinct unknown the block reads (aliases share
  // one; constants have none, slot -1), so a Dual carries n_slots
  // derivatives instead of one per local variable.
  std::vector<int> slot;         // local -> direction or -1
  std::vector<int> slot_local;   // direction -> a local variable with it
  // Every row of the block was eliminated as an alias: its Jacobian rows
  // are not needed, and a framework block's rows hold by construction.
  bool all_eliminated = false;
};
// A component's rows, and the blocks the framework adds at nodes (the
// structure fills in vars, rows and labels): Kirchhoff's sum of the through
// variables (vars: the flows), ...
std::unique_ptr<Block> make_component_block();
// (with total_first: vars[0] is the sum of the others, a group's flow)
std::unique_ptr<Block> make_flow_sum_block(bool total_first = false);
// ... the mixed inStream temperature of a node of three or more pneumatic
// ports,
// vars: [T_in_i, (m_flow_j, T_out_j) for `ports` ports j != i, (W, H) of
// groups of the other ports]
std::unique_ptr<Block> make_stream_mix_block(int ports);
// ... the sums of such a group (two rows), vars: [W, (m_flow_j, T_out_j)
// of the group's ports, H],
std::unique_ptr<Block> make_stream_sum_block();
// ... ds/dt = v of a translational node, vars: [s, v],
std::unique_ptr<Block> make_kinematic_block();
// ... an unknown held at a constant: the default value of an unconnected
// optional input, or the ambient temperature of an unconnected heat port its
// component holds there (Component::unconnected_heat_port_at_ambient),
// vars: [it].
std::unique_ptr<Block> make_fixed_value_block(double value);
// ... the heat flow into an unconnected (insulated) heat port, the
// context's rest_heat conductance times (T_ambient - T), vars: [Q, T] (a
// steady start's rest; 0 in the run),
std::unique_ptr<Block> make_rest_heat_block(double T_ambient);
// The stream-mixing rows: their temperatures stay unknowns of IDA.
bool is_stream_mix(const Block& b);
// A group's sums for the mixes of a large node.
bool is_stream_sum(const Block& b);

// Copy a block's local variables (and their derivatives) out of the global
// vectors (the hot path: every block evaluation starts here).
void gather(const Block& b, const double* y, const double* yp, double* ly, double* lyp);

// A block's rows at one point, with the Pattern scalar (which locals each
// row reads, and which of them nonlinearly) and with Dual numbers, one
// direction per local (dF/d local, times the local's alias sign). y and yp
// are the unknowns the blocks read (after alias elimination).
void evaluate_structure(const Block& b, double t, const double* y, const double* yp, const EvalContext& ctx,
                        std::vector<Pattern>& pr, std::vector<Dual>& dr);

// "{a.port, b.port}": the ports of a node, for messages and row names.
std::string node_text(const Circuit& c, const std::vector<PortId>& ports);

// The compressed-column (CSC) form KLU takes of the pattern whose column c
// holds the rows cols[c]; returns the position in row_idx of each (row,
// column) entry.
std::map<std::pair<int, int>, int> compress_columns(const std::vector<std::set<int>>& cols,
                                                    std::vector<long>& col_ptr, std::vector<long>& row_idx);

}  // namespace pneumo
