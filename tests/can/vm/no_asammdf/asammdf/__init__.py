# Put first on PYTHONPATH inside the VM only (tests/can/vm/mdtool_vcan.sh, vcan_e2e.sh):
# python-can imports asammdf when it is installed, and asammdf's compiled
# module asammdf.blocks.cutils (8.1.2) executes instructions the VM's emulated CPU (QEMU
# TCG, default model) lacks: the process dies with SIGILL. python-can treats
# this ImportError as "MF4 not available" and everything else works.
raise ImportError("asammdf hidden in the VM (tests/can/vm/no_asammdf)")
