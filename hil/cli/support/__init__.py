"""What the subcommands share and no subcommand owns: option types, output, the station and store
options, output-path checks, progress printers and signal handling. Command modules import from
here, never from each other."""
