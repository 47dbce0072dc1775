/*
 * `loadid plot PATH`: figures of how an estimate came about. PATH is a
 * recording (can.log and lcm.log), which loadidd --offline --trace (the
 * loadidd beside this program) estimates into OUT first, or a trace CSV, or
 * a folder holding some (and loadid-demo's runs.csv). The drawing is
 * loadid_plot.py's (tools/plot), found beside the program as
 * ../share/loadid/loadid_plot.py (the build tree has a copy there, the
 * install puts it there), run by $LOADID_PYTHON, else the build tree's
 * venv (../../venv/bin/python), else python3.
 */
#ifndef LOADID_CLI_PLOT_H
#define LOADID_CLI_PLOT_H

/* config: the configuration to estimate a recording with (NULL: none; a
 * recording then needs one); out: the figures' folder (NULL: PATH/plots
 * for a recording, beside the traces otherwise); publish_every: the
 * trace's period in samples (0: loadidd's default). Returns the exit
 * status: 0, 1 (a failure, said on stderr) or 2 (usage). */
int loadid_cli_plot(const char *prog, const char *config, const char *path, const char *out,
                    int publish_every);

#endif /* LOADID_CLI_PLOT_H */
