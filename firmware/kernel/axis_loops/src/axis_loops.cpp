// Explicit instantiations for the two kernel scalars (float, Q7.24).
#include "maglev/io/axis.hpp"
#include "maglev/axis_loops/biquad.hpp"
#include "maglev/axis_loops/defaults.hpp"
#include "maglev/axis_loops/internal_model.hpp"
#include "maglev/axis_loops/pid2dof.hpp"

namespace maglev::kernel {

template class Pid2Dof<float>;
template class Pid2Dof<numeric::Q7_24>;
template class InternalModelRegulator<float>;
template class InternalModelRegulator<numeric::Q7_24>;
template LoopDesignError design_pid2dof<float>(const Pid2DofConfig&, double, Pid2DofCoefficients<float>*);
template LoopDesignError design_pid2dof<numeric::Q7_24>(const Pid2DofConfig&, double,
                                                        Pid2DofCoefficients<numeric::Q7_24>*);
template LoopDesignError design_biquad<float>(const BiquadConfig&, double, BiquadCoefficients<float>*);
template LoopDesignError design_biquad<numeric::Q7_24>(const BiquadConfig&, double,
                                                       BiquadCoefficients<numeric::Q7_24>*);
template float biquad_update<float>(const BiquadCoefficients<float>&, BiquadState<float>&, float);
template numeric::Q7_24 biquad_update<numeric::Q7_24>(const BiquadCoefficients<numeric::Q7_24>&,
                                                      BiquadState<numeric::Q7_24>&, numeric::Q7_24);
template LoopDesignError design_internal_model<float>(const InternalModelConfig&, double,
                                                      InternalModelCoefficients<float>*);
template LoopDesignError design_internal_model<numeric::Q7_24>(const InternalModelConfig&, double,
                                                               InternalModelCoefficients<numeric::Q7_24>*);

}  // namespace maglev::kernel
