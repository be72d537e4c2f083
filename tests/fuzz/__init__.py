"""A fuzzer of the FMU's FMI 2.0 and 3.0 C interfaces.

``bindings`` loads the shared libraries with ctypes (no fmpy: the fuzzer must run inside a process
whose allocator is AddressSanitizer's; ``binding_base``, ``fmi2_binding`` and ``fmi3_binding`` hold
its parts), ``model`` reads the variables from modelDescription.xml, ``sequences`` draws random call
sequences as plain JSON actions, ``executor`` runs them against the oracle (``oracle``: the
verdict; ``fmu_states``: the actions on FMU states), and ``runner`` drives it all in a
sanitizer-enabled subprocess, minimises what fails and replays the corpus (tests/fuzz_corpus/).
``extreme_inputs`` replays a list of extreme inputs through the runner and the CLI and prints the
answer each gets (BENCHMARKS.md, "Extreme inputs").
"""
