package rtaccel.iu

import rtaccel.config.TriTest
import rtaccel.fp.{DspShape, FpFormat, Stager}

/** What shapes the IU's arithmetic pipes (BoxPipe, TriPipe, WatertightPipe) and the jobs and results they carry: the
  * view of PlatformParams these modules take (`PlatformParams.pipes`). Two platforms with equal views build the same
  * pipes, so PipeLatencies memoizes on it. The family's DSP tile and delay chains enter only with a register budget
  * (without one no Stager places a register, whatever the family), and so do its LUTs' inputs.
  */
final case class PipeParams(m: Int, tuBits: Int, boxFormat: FpFormat, boxSlackUlps: Int, triTest: TriTest, triFormat: FpFormat,
                            divStages: Int, stageBudget: Option[Int], dspShape: Option[DspShape], delayRamCycles: Option[Int],
                            lutInputs: Int, triInterval: Int = 1, boxInterval: Int = 1) {
  /** A register placer for one module's datapath at this budget (each module takes its own). */
  def pipe: Stager = stageBudget.fold(new Stager(None))(b => new Stager(Some(b), dspShape.get, delayRamCycles, lutInputs))
}
