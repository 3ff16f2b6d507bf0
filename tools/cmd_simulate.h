/* SPDX-License-Identifier: MIT */
/* cmd_simulate.h: btdftab simulate, the Monte Carlo goniophotometer (btdf_sim.h). */
#ifndef BTDFTAB_CMD_SIMULATE_H
#define BTDFTAB_CMD_SIMULATE_H

/* argv[0] is "simulate"; prov the command line for the report. Returns the exit status. */
int cmd_simulate(const char *prog, int argc, char **argv, const char *prov);

#endif
