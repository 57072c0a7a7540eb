#include "framework/study/communicator.hpp"

#include <cstdlib>
#include <stdexcept>

#ifdef PNEUMO_WITH_MPI
#include <mpi.h>
#endif

namespace pneumo::study {

namespace {

int env_int(const char* name) {
  const char* v = std::getenv(name);
  return v ? std::atoi(v) : -1;
}

// World size announced by the launcher (OpenMPI, PMIx, Hydra/PMI), or -1.
int launcher_size() {
  for (const char* n : {"OMPI_COMM_WORLD_SIZE", "PMIX_SIZE", "PMI_SIZE", "MPI_LOCALNRANKS"}) {
    const int v = env_int(n);
    if (v > 0) return v;
  }
  return -1;
}

#ifdef PNEUMO_WITH_MPI
class MpiCommunicator final : public Communicator {
 public:
  MpiCommunicator() {
    int initialised = 0;
    MPI_Initialized(&initialised);
    if (!initialised) MPI_Init(nullptr, nullptr);
    MPI_Comm_rank(MPI_COMM_WORLD, &rank_);
    MPI_Comm_size(MPI_COMM_WORLD, &size_);
  }
  ~MpiCommunicator() override {
    int finalised = 0;
    MPI_Finalized(&finalised);
    if (!finalised) MPI_Finalize();
  }
  int rank() const override { return rank_; }
  int size() const override { return size_; }
  void broadcast(std::string& text) override {
    long n = static_cast<long>(text.size());
    MPI_Bcast(&n, 1, MPI_LONG, 0, MPI_COMM_WORLD);
    text.resize(static_cast<std::size_t>(n));
    if (n > 0) MPI_Bcast(text.data(), static_cast<int>(n), MPI_CHAR, 0, MPI_COMM_WORLD);
  }
  std::vector<std::string> gather(const std::string& text) override {
    int n = static_cast<int>(text.size());
    std::vector<int> sizes(size_), offsets(size_, 0);
    MPI_Gather(&n, 1, MPI_INT, sizes.data(), 1, MPI_INT, 0, MPI_COMM_WORLD);
    std::string all;
    if (rank_ == 0) {
      long total = 0;
      for (int r = 0; r < size_; ++r) offsets[r] = static_cast<int>(total), total += sizes[r];
      all.resize(static_cast<std::size_t>(total));
    }
    MPI_Gatherv(text.data(), n, MPI_CHAR, all.data(), sizes.data(), offsets.data(), MPI_CHAR, 0, MPI_COMM_WORLD);
    std::vector<std::string> out;
    if (rank_ == 0)
      for (int r = 0; r < size_; ++r) out.push_back(all.substr(offsets[r], sizes[r]));
    return out;
  }
  void barrier() override { MPI_Barrier(MPI_COMM_WORLD); }
  void abort(int code) override { MPI_Abort(MPI_COMM_WORLD, code); }

 private:
  int rank_ = 0, size_ = 1;
};
#endif

}  // namespace

bool launched_by_mpi() { return launcher_size() > 0; }

bool mpi_available() {
#ifdef PNEUMO_WITH_MPI
  return true;
#else
  return false;
#endif
}

Communicator& process_communicator() {
#ifdef PNEUMO_WITH_MPI
  if (launched_by_mpi()) {
    static MpiCommunicator mpi;
    return mpi;
  }
#else
  if (launcher_size() > 1)
    throw std::runtime_error("started by mpirun with " + std::to_string(launcher_size()) +
                             " ranks, but this pneumo was built without MPI (install libopenmpi-dev and rebuild)");
#endif
  static Communicator single;
  return single;
}

}  // namespace pneumo::study
