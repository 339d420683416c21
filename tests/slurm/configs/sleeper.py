#!/usr/bin/python3
"""Test step: sleeps $MELTLAB_TEST_SLEEP_S seconds (default 0: none), then writes FOLDER/slept.txt.
The sleep comes from the environment, not the arguments, so that a resumed run (without it)
has the same content hash as the cancelled one."""
import os
import sys
import time

time.sleep(float(os.environ.get("MELTLAB_TEST_SLEEP_S", "0")))
os.makedirs(sys.argv[1], exist_ok=True)
with open(os.path.join(sys.argv[1], "slept.txt"), "w") as f:
    f.write("done\n")
