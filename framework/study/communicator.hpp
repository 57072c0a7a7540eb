// Processes that share a study. Without MPI there is one process (rank 0 of
// 1). Under `mpirun -np N pneumo ...` (pneumo built with OpenMPI) each rank
// runs its share of the runs and rank 0 collects the results.
#pragma once

#include <memory>
#include <string>
#include <vector>

namespace pneumo::study {

class Communicator {
 public:
  virtual ~Communicator() = default;
  virtual int rank() const { return 0; }
  virtual int size() const { return 1; }
  // Rank 0's `text` reaches every rank.
  virtual void broadcast(std::string& text) { (void)text; }
  // Every rank's `text`, in rank order, on rank 0 (others get an empty list).
  virtual std::vector<std::string> gather(const std::string& text) { return {text}; }
  virtual void barrier() {}
  // Whether a failure on one rank must stop the others (MPI_Abort).
  virtual void abort(int code) { (void)code; }
};

// True when this process was started by an MPI launcher (mpirun/mpiexec).
bool launched_by_mpi();
// The communicator for this process: MPI if launched by mpirun (initialising
// MPI once; finalised at exit), otherwise a single process. Throws if
// launched by mpirun with more than one rank but built without MPI.
Communicator& process_communicator();
// Whether this build has MPI support.
bool mpi_available();

}  // namespace pneumo::study
