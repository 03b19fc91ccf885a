#pragma once
// `fullarm access --population N`: which share of a population of technicians can reach a scene's
// target (each reach mode) and push the task's force there, with and without bracing; the
// population over threads, shards (`--shard i/N`, then `fullarm access merge`) or the ranks of
// an MPI job; summary.json, technicians.csv and the report with the shares and a map.

#include "access_command.hpp"

namespace fullarm::app {

/// Runs the population of `options` (options.population set): plans the nominal arm's reach,
/// then evaluates every technician (accessibility::evaluateTechnician) in a core sweep named
/// "technicians" on options.threads workers. Under `mpirun` (OpenMPI's OMPI_COMM_WORLD_SIZE in
/// the environment) the technicians are spread over the ranks and rank 0 writes the outputs.
/// With --shard the run writes its shard (technicians.sweep and population.json) to --out for
/// `fullarm access merge`; otherwise summary.json, technicians.csv and report.html.
/// @return 0 (the answer is a share, not a verdict)
/// @throws core::ConfigError for bad options (no --force, a bad --shard, --shard without --out,
///   a bad mix) or inputs (exit 2)
int runAccessPopulation(const AccessOptions& options);

/// `fullarm access merge`: reads the shards (each technicians.sweep with its population.json), checks that they are the
/// shards of one population (the same task, every shard once) and writes the population's outputs to --out.
/// @return 0
/// @throws core::ConfigError naming the folder and what is wrong (exit 2)
int runAccessMerge(const AccessMergeOptions& options);

}  // namespace fullarm::app
