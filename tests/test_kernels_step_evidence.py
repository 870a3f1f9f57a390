"""The step evidence on Eq. 9's local term (kernels/*/step_evidence.py): the generic contract from
the case table (odd sizes, one row, one column, one frame, strided inputs, aliasing, empty input,
threads, backends against each other), and checks of its own."""
from kernel_harness import contract, pytest_generate_tests  # noqa: F401  (the kernel_backend fixture)

TestContract = contract("step_evidence")
