package rtaccel.tu

import chisel3._
import chiseltest._
import org.scalatest.funsuite.AnyFunSuite
import scala.util.Random

/** The stack as the TU drives it: one push, pop or clear per cycle. */
class FullStackHarness(depth: Int, topInRegister: Boolean) extends Module {
  val io = IO(new Bundle {
    val push = Input(Bool())
    val pop = Input(Bool())
    val clear = Input(Bool())
    val in = Input(UInt(16.W))
    val out = Output(UInt(16.W))
    val empty = Output(Bool())
    val full = Output(Bool())
  })
  private val s = new FullStack(UInt(16.W), depth, topInRegister)
  io.empty := s.empty
  io.full := s.full
  io.out := 0.U
  when(io.clear) { s.clear() }
    .elsewhen(io.push) { s.push(io.in) }
    .elsewhen(io.pop) { io.out := s.pop() }
}

/** The TU's full stack against a Scala list, every cycle: `empty`, `full` and each popped entry, under random pushes
  * (up to full), pops (down to empty) and clears, for depths that are and are not powers of two, with the top entry
  * in the RAM and in a register (PIPELINE).
  */
class FullStackSpec extends AnyFunSuite with ChiselScalatestTester {
  for (depth <- Seq(1, 2, 5, 8); top <- Seq(false, true))
    test(s"depth $depth, top in ${if (top) "a register" else "the RAM"}: the entries of a stack, last in first out") {
      test(new FullStackHarness(depth, top)) { dut =>
        val rnd = new Random(depth * 2 + (if (top) 1 else 0))
        var ref = List[Int]()
        var pops = 0; var fullCycles = 0
        for (cycle <- 0 until 3000) {
          assert(dut.io.empty.peek().litToBoolean == ref.isEmpty, s"cycle $cycle: empty with ${ref.length} held")
          assert(dut.io.full.peek().litToBoolean == (ref.length == depth), s"cycle $cycle: full with ${ref.length} held")
          if (ref.length == depth) fullCycles += 1
          // runs of pushes and of pops, so the stack fills and drains; a rare clear
          val op = rnd.nextInt(100)
          val clear = op == 0
          val push = !clear && (cycle / 7) % 2 == 0 && ref.length < depth && op % 3 != 0
          val pop = !clear && !push && ref.nonEmpty && op % 2 == 0
          val v = rnd.nextInt(1 << 16)
          dut.io.clear.poke(clear.B); dut.io.push.poke(push.B); dut.io.pop.poke(pop.B); dut.io.in.poke(v.U)
          if (pop) {
            assert(dut.io.out.peekInt().toInt == ref.head, s"cycle $cycle: popped ${dut.io.out.peekInt()} for ${ref.head}")
            ref = ref.tail; pops += 1
          }
          if (push) ref = v :: ref
          if (clear) ref = Nil
          dut.clock.step()
        }
        assert(pops > 300 && fullCycles > 30, s"only $pops pops, $fullCycles cycles full")
      }
    }
}
