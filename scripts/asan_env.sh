# Sourced by `make test-asan`: the sanitizer options the whole test suite runs under. Each one
# is here for a reason measured on this project; the build itself stops at the first report
# (-fno-sanitize-recover=all), so no option below lets an error pass.
#
# ASAN_OPTIONS
#   detect_leaks=0       LeakSanitizer off. Open MPI keeps what MPI_Init allocates (hwloc's
#                        topology, PMIx, the component registry) until exit, and MPI_Finalize
#                        does not free it: every test that starts the solvers' MPI (all CLI
#                        tests, every hypre/MueLu test) would report those as leaks. Our own
#                        objects are owned by RAII types; a use after free or an overflow is
#                        still reported.
#   abort_on_error=1     a report ends in SIGABRT rather than ASan's default exit(1): a child the
#                        tests start (xpbd-bench, mpirun's ranks) that is expected to fail cannot
#                        pass a sanitizer report off as its expected non-zero exit.
# UBSAN_OPTIONS
#   print_stacktrace=1   the report names the call path, not just the line.
export ASAN_OPTIONS=detect_leaks=0:abort_on_error=1
export UBSAN_OPTIONS=print_stacktrace=1
