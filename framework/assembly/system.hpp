// Assembly: a Circuit becomes one DAE F(t, y, y') = 0. System is the
// assembled model - its structure and reductions, never changed once built,
// so that integrations and threads share one; an Evaluator
// (evaluator.hpp) is one integration's view of it, with the modes and the
// scratch a run changes. The rooms are one file each:
//
//  * blocks.cpp     - equation blocks and their gather of locals;
//  * structure.cpp  - nodes, unknowns, blocks, the sparsity pattern (found
//                     once with the Pattern scalar; IDASetId from the same
//                     pass) and the structural (index-1) check;
//  * aliases.cpp    - the first reduction: y_b = +-y_a and constants
//                     substituted;
//  * explicit.cpp   - the second: unknowns one equation gives explicitly,
//                     solved inside the residual in dependency order;
//  * evaluator.cpp  - residual and Newton matrix (AD, Schur complement);
//  * events.cpp     - roots, time events, modes;
//  * probes.cpp     - outputs and integrands at a point.
//
// Three numberings of unknowns: "full" (the netlist's, before reductions),
// "m-level" (after alias elimination: what the blocks' vars index) and
// IDA's (the m-level unknowns that are not solved explicitly).
#pragma once

#include <memory>
#include <random>
#include <string>
#include <vector>

#include "framework/assembly/blocks.hpp"
#include "framework/model/circuit.hpp"

namespace pneumo {

struct EventLogEntry {
  double t = 0.0;
  std::string component;
  std::string message;
  std::string tag;  // EventResult::tag
};

struct AssemblyOptions {
  // Substitute alias equations (y_b = +-y_a; a variable a row sets to a
  // constant: flow = 0 at a lone port, an unconnected input's default, a
  // source's pressure and temperature) instead of handing them to IDA: on
  // the cushion rig 55 unknowns become 22 and a run takes 40 % less time.
  // Eliminated variables stay readable (outputs, probes, events see them
  // through the alias map). The stream temperatures at nodes of three or
  // more pneumatic ports are kept (see eliminate_aliases()). false: every
  // unknown of the netlist goes to IDA (`--keep-aliases`; the component
  // Jacobian checks use it to see each component's rows as written).
  bool eliminate_aliases = true;
  // After alias elimination, solve every algebraic unknown that one
  // equation gives explicitly - an equation without y' that is linear, with
  // a constant coefficient, in that unknown and whose other unknowns are
  // states or unknowns solved before it (port pressures p = (kappa-1) U/V,
  // throttle flows, stream temperatures, forces) - by one evaluation and a
  // division inside every residual call, in dependency order, so that IDA
  // integrates (nearly) only the states: on the cushion rig 22 unknowns
  // become 11. The Jacobian IDA sees is the exact Schur complement of the
  // AD Jacobian. Needs eliminate_aliases; rows of components with discrete
  // modes are never used (an event could change them).
  bool eliminate_explicit = true;
  // Give every heat port left unconnected (insulated) a conductance to the
  // ambient temperature that Evaluator::set_resting switches on: a steady
  // start's settling then ends with the gas at the temperature a long rest
  // gives it, where the run's adiabatic walls would keep the heat of
  // filling. Off, the port's heat flow is the constant 0 as always.
  bool rest_heat = false;
};

// Lower bound of the typical magnitude of a quantity in `unit` (SI unit
// text, e.g. "Pa", "kg"): scales absolute tolerances; 1 for other units.
double nominal_floor(const std::string& unit);

// A fixed list of probes grouped by component (System::probe_set), for
// evaluating them all at many points (Evaluator::probe_all): outputs and
// integrands then gather each component's variables and run its
// observables' shared computation once per point, not once per probe.
struct ProbeSet {
  struct Group {
    int component = -1;
    std::vector<int> observables;  // observable indices of the component
    std::vector<int> slots;        // where each value goes in the output
  };
  std::vector<Group> groups;       // components with observable probes
  std::vector<Probe> locals;       // local-variable probes (no observe call)
  std::vector<int> local_slots;
  std::size_t size = 0;
  mutable std::vector<double> scratch;  // one group's values
  // Found at probe_set() by evaluating the probes with the explicitly solved
  // unknowns (then all y') set to NaN at three points: whether the values
  // need expand() (or only the states), and whether they read any y' (the
  // solver then interpolates y' for outputs too).
  bool reads_explicit = true;
  bool reads_yp = true;
};

// Working state of the rooms' builders (structure.cpp, aliases.cpp,
// explicit.cpp), defined there.
struct NodeLayout;
struct AliasClasses;
struct ExplicitRows;
struct ExplicitOrder;

// A component's ExternalInputSpec, found in the circuit.
struct ExternalInput {
  std::string name;  // the component's
  ExternalInputSpec spec;
  int mode = 0;  // index into Evaluator::modes()
};

class System {
 public:
  // Takes ownership of the circuit. Throws InputError (dangling or
  // mismatched ports) or StructureError (singular / higher index).
  explicit System(Circuit circuit, const AssemblyOptions& options = {});
  ~System();
  System(const System&) = delete;
  System& operator=(const System&) = delete;

  int size() const { return n_; }
  // Unknowns before alias elimination (size() counts those left for IDA).
  int full_size() const { return aliases_.n_full; }
  // Unknowns solved explicitly inside the residual (eliminate_explicit).
  int explicit_size() const { return static_cast<int>(plan_.unknowns.size()); }
  const Circuit& circuit() const { return circuit_; }
  const GasModel& gas() const { return circuit_.gas; }

  const std::vector<long>& col_ptr() const { return col_ptr_; }
  const std::vector<long>& row_idx() const { return row_idx_; }
  long nnz() const { return static_cast<long>(row_idx_.size()); }
  // 1.0 for differential variables (some equation has its y'), 0.0 algebraic.
  const std::vector<double>& differential() const { return id_; }
  // How many of IDA's rows are stream-mixing rows (is_stream_mix, and the
  // groups' sums of large nodes): rows without y', as many as the
  // algebraic unknowns they determine.
  int stream_mixing_rows() const;
  // Typical magnitude of each variable, for absolute tolerances.
  const std::vector<double>& nominal() const { return nominal_; }
  const std::vector<std::string>& variable_names() const { return var_names_; }
  // The equation behind IDA's residual row `row` ("component: equation name").
  std::string row_name(int row) const;

  void start_values(std::vector<double>& y0, std::vector<double>& yp0) const;
  // The pressures (IDA's indices) of pneumatic junctions no component
  // starts - no volume there: those guess_junction_pressures started from
  // their neighbours, and those it left at ambient - and the distinct start
  // pressures the components give, ascending: other starts for them when
  // the guess finds no consistent values (IdaRun::consistent_ic).
  struct Junctions {
    std::vector<int> unguessed, guessed;
  };
  Junctions junction_pressures() const;
  const std::vector<double>& start_pressure_levels() const { return pressure_levels_; }

  // Whether the System has rest-heat rows (AssemblyOptions::rest_heat;
  // Evaluator::set_resting switches them on).
  bool has_rest_heat() const { return rest_heat_ports_; }
  // The conductance of such a port while resting (W/K): fast next to any
  // chamber's filling, a rest of seconds of settling time.
  static constexpr double kRestHeatConductance = 1.0;

  int n_roots() const { return n_roots_; }
  std::vector<double> time_events() const;
  // The values programs may set while the circuit runs (Component::
  // external_inputs), in component order.
  std::vector<ExternalInput> external_inputs() const;

  // The components (indices into circuit().components) whose equations read
  // IDA's unknown `i`: a node's unknown is read by every component at the
  // node, a component's internal unknown by that component.
  std::vector<int> components_reading(int i) const;
  // The circuit's nodes, each the ports it joins: connections that share a
  // port are one node; an optional port left unconnected is a node alone.
  const std::vector<std::vector<PortId>>& nodes() const { return nodes_; }
  // Whether a local variable of component `component` (an index into its
  // local_variable_names) is a constant after alias elimination: a node
  // held by a source's pressure or the atmosphere, a flange on a fixed
  // wall. Always false when the System keeps its aliases.
  bool holds_constant(int component, int local) const;

  // Group `probes` by component (Evaluator::probe_all evaluates them).
  ProbeSet probe_set(const std::vector<Probe>& probes) const;

 private:
  friend class Evaluator;  // reads the structure and the plans

  // Explicit unknowns solved together: (block, indices into
  // ExplicitPlan::unknowns the block's rows give), in level order.
  using Stage = std::vector<std::pair<int, std::vector<int>>>;

  // The structure (structure.cpp).
  void build_nodes();
  int new_var(std::string name, double start, unsigned char kind, double nominal);
  void add_node_variables(NodeLayout& l);
  void add_component_block(int ci, NodeLayout& l, int& mode, int& root);
  void add_internal_variables(const Component& comp, Block& b);
  void add_node_block(std::unique_ptr<Block> b, std::string label, std::vector<std::string> row_names, NodeLayout& l,
                      int node);
  void guess_junction_pressures(const NodeLayout& l);
  void route_streams(NodeLayout& l);
  void add_node_balances(NodeLayout& l);
  void build_pattern();
  void check_structure() const;
  // "component: equation [file:line]" of full row `row`.
  std::string equation_name(int row) const;
  // The start values (pass 0) or a random perturbation of them (passes 1,
  // 2): the points at which assembly probes the equations' structure.
  void check_point(int pass, std::mt19937& rng, std::vector<double>& y0, std::vector<double>& yp0) const;
  void build_slots();

  // The reductions (aliases.cpp, explicit.cpp).
  void eliminate_aliases();
  std::vector<int> renumber_aliases(AliasClasses& classes, const std::vector<char>& eliminated);
  void reduce_pattern(AliasClasses& classes, const std::vector<int>& reduced);
  void eliminate_explicit();
  ExplicitRows explicit_rows() const;
  void record_row(const Block& b, const Pattern& p, const Dual& d, int pass, ExplicitRows& rows, int q) const;
  std::vector<int> number_explicit(const ExplicitRows& rows, const ExplicitOrder& o);
  std::vector<double> schur_pattern(const ExplicitRows& rows, const ExplicitOrder& o,
                                    const std::vector<int>& ida_row_of_m);
  void plan_stages(const ExplicitRows& rows, const ExplicitOrder& o);
  void find_root_inputs();
  // The explicit unknowns (indices into plan_.unknowns) block b's root
  // functions read: each of its explicit locals set to NaN in turn, at the
  // start values and two perturbations, the roots stay finite if not.
  std::vector<int> explicit_root_inputs(const Block& b) const;
  // Probing (probes.cpp).
  // Block b's locals at the start values (perturbed by pass), with the
  // explicit unknowns and/or all y' set to NaN: a root function or probe that
  // stays finite does not read them.
  void poisoned_locals(const Block& b, int pass, std::mt19937& rng, bool nan_explicit, bool nan_yp, double* ly,
                       double* lyp) const;

  Circuit circuit_;
  std::vector<std::vector<PortId>> nodes_;
  std::vector<std::unique_ptr<Block>> blocks_;
  int n_ = 0;
  std::vector<std::string> var_names_;
  std::vector<double> start_value_;
  std::vector<unsigned char> start_kind_;
  std::vector<char> junction_;  // a pneumatic node's pressure no component starts: 1, 2 once guessed
  std::vector<double> pressure_levels_;
  std::vector<double> nominal_;
  std::vector<double> id_;
  std::vector<long> col_ptr_, row_idx_;
  std::vector<std::vector<int>> dep_y_, dep_yp_;  // per row: structural columns
  // The components' initial modes: the assembly probes the equations with
  // them (an Evaluator starts from them too).
  std::vector<double> modes_;
  // The conductance the rest-heat rows have while the structure is found
  // (kRestHeatConductance if there are any), so that the reductions see
  // their dependence on T (with 0, Q = 0 would pass for a constant).
  double rest_heat_ = 0.0;
  bool rest_heat_ports_ = false;
  int n_roots_ = 0;
  std::vector<int> root_blocks_;  // the blocks of components with root functions

  // The alias reduction (aliases.cpp): rows solved by substitution (y_b =
  // +-y_a, or a node with one port: flow = 0, an unconnected input = its
  // default) are still evaluated and must stay exactly satisfied; kept rows
  // map to the alias level's rows.
  struct AliasMap {
    int n_full = 0;                          // the netlist's unknowns (and rows)
    std::vector<int> row_of;                 // full row -> alias-level row, -1 if eliminated
    std::vector<int> eliminated;             // full rows eliminated
    std::vector<double> eliminated_nominal;  // scale of each, for the check
    std::vector<int> checked;                // indices into eliminated of rows evaluated per residual
  } aliases_;

  // The explicit reduction (explicit.cpp). "m-level": the m unknowns after
  // alias elimination, which the blocks' vars index; IDA sees n_ of them.
  struct ExplicitUnknown {
    int var = -1;    // m-level unknown
    int row = -1;    // full row that gives it
    double coef = 0.0;  // dF_row / dy_var (constant)
    int level = 0;   // 1 + the highest level among the unknowns the row reads
    std::vector<std::pair<long, int>> entries;  // (j1 position, m-level column) of the row
    int d0 = 0, dn = 0;  // its derivative d var / d y_IDA: d_cols[d0, d0 + dn)
    std::vector<int> deps;  // m-level unknowns the row may read (its level's basis)
  };
  struct KeptRow {
    int row = -1;  // full row
    std::vector<std::pair<long, int>> entries;  // (j1 position, m-level column)
    std::vector<std::pair<int, long>> out;      // (IDA column, IDA CSC position)
  };
  struct ExplicitPlan {
    int m = 0;
    std::vector<ExplicitUnknown> unknowns;  // in level order
    std::vector<int> of_m;                  // m-level unknown -> index in unknowns or -1
    std::vector<int> ida_to_m, m_to_ida;    // IDA unknown <-> m-level unknown (-1: explicit)
    std::vector<int> ida_row_of_full;       // full row -> IDA row, -1 if eliminated
    std::vector<Stage> stages;              // per level
    std::vector<int> final_blocks;          // blocks evaluated for IDA's rows (and the alias checks)
    std::vector<std::pair<int, int>> kept_full_rows;  // (full row, IDA row) of IDA's rows
    std::vector<double> m_start;
    std::vector<std::string> m_names;
    std::vector<long> j1_col_ptr, j1_row_idx;  // the m-level Jacobian's pattern
    std::vector<int> d_cols;
    std::vector<KeptRow> kept_rows;
    // Whether some root function reads explicit unknowns (else roots are
    // evaluated on the states alone), and the part of the stages that solves
    // those unknowns and the ones they depend on, in level order: root
    // checks run it, not the whole expand().
    bool any_roots_read_explicit = false;
    Stage root_stages;
  } plan_;

};

}  // namespace pneumo
