// An algorithm's abort, told to the pipeline in the way its VTK understands.
#ifndef asrt_AlgorithmAbort_h
#define asrt_AlgorithmAbort_h

namespace asrt
{
namespace detail
{
// VTK with the abort API of 2023 (ParaView 5.11's VTK 9.2.20230111 and later): CheckAbort() marks
// the outputs aborted, so that downstream filters see ABORTED and stop too.
template<class Algorithm>
auto reportAbort(Algorithm* algorithm, int) -> decltype(algorithm->CheckAbort(), void())
{
  algorithm->CheckAbort();
}
// Older VTK (9.1): the AbortExecute flag that stopped the work is all there is.
template<class Algorithm>
void reportAbort(Algorithm*, long)
{
}
}

/// Called on the pipeline's thread once an algorithm has stopped its work for AbortExecute: the
/// same sources build against VTK 9.1 and against ParaView's VTK.
template<class Algorithm>
void reportAbort(Algorithm* algorithm)
{
  detail::reportAbort(algorithm, 0);
}
}

#endif
