# Sourced by the MPI tests after their one-process run: sets `ranks`, the arguments that start
# two ranks of glint with mpiexec as root.
#
# Under the sanitizers (.ci/sanitize) the ranks get the suppressions explicitly, and no leak
# check: Open MPI's collective components, loaded with dlopen, keep what they allocate on the
# first MPI_Allgather past MPI_Finalize, and their frames are unknown modules no suppression can
# name. The one-process run before keeps the leak check on the same code.
ranks=(--allow-run-as-root --oversubscribe)
for var in ASAN_OPTIONS UBSAN_OPTIONS LSAN_OPTIONS; do
  [[ -n ${!var:-} ]] && ranks+=(-x "$var")
done
[[ -n ${ASAN_OPTIONS:-} ]] && export ASAN_OPTIONS="$ASAN_OPTIONS:detect_leaks=0"
ranks+=(-np 2)
