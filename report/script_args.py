"""What the report's benchmark scripts share: `SCRIPT MELTLAB DIR [--quick | --full]` and running
a command with its output in a log file."""
import subprocess
import sys


def meltlab_out_quick(argv, doc):
    """(meltlab, out_dir, quick) from argv, or None after printing why (usage or the first unknown
    argument) to stderr."""
    if len(argv) < 3:
        print(doc, file=sys.stderr)
        return None
    unknown = [a for a in argv[3:] if a not in ("--quick", "--full")]
    if unknown:
        print(f"{argv[0].rsplit('/', 1)[-1]}: unknown argument {unknown[0]}", file=sys.stderr)
        return None
    return argv[1], argv[2], "--quick" in argv[3:]


def run(cmd, log):
    """Runs cmd with stdout and stderr in the file `log`; a non-zero exit raises."""
    with open(log, "w") as fh:
        subprocess.run(cmd, check=True, stdout=fh, stderr=subprocess.STDOUT)
