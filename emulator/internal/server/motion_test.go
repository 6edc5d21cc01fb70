package server

// Motion over TCP with the simulated clock: moves end on their target, velocities integrate as an ideal
// differential drive (guide 4.3; E-SRV-005, E-SRV-009, E-SRV-016, E-PAR-018/019/023, E-REP-005, E-REP-012).

import (
	"bytes"
	"math"
	"testing"

	"pltf/emulator/internal/model"

	pc "platformctrl"
)

func running(h *harness, mode pc.MotionMode) *conn {
	c := h.dial(h.ports[0])
	c.send(&pc.ConnectToPltfRequest{}, &pc.InitPltfRequest{}, &pc.SetModeRequest{Mode: mode}, &pc.StartRequest{})
	if s := c.status(); s.OperationState != pc.StOpRunning || s.MotionMode != mode {
		h.t.Fatalf("not running in mode %d: %d %d", mode, s.OperationState, s.MotionMode)
	}
	return c
}

func near(a, b, tol float64) bool { return math.Abs(a-b) <= tol }

func expectPose(t *testing.T, c *conn, x, y, th float64, how string) *pc.GetPositionReply {
	t.Helper()
	p := c.position()
	if !near(float64(p.X), x, 1) || !near(float64(p.Y), y, 1) || !near(model.Normalize(p.Angle-th), 0, 1e-6) {
		t.Fatalf("%s: at (%d, %d, %.4f rad), want (%.0f, %.0f, %.4f)", how, p.X, p.Y, p.Angle, x, y, th)
	}
	return p
}

func TestPositionAtRestIsTheVectorsBytes(t *testing.T) {
	h := start(t)
	c := h.dial(h.ports[0])
	c.send(&pc.GetPositionRequest{})
	got, _ := c.readFrame()
	if want := loadVectors(t, "replies.json")["reply_get_position_zero"].bytes(t); !bytes.Equal(got, want) {
		t.Fatalf("got %x\nwant %x", got, want)
	}
}

func TestMoveRelEndsAtTheTargetPose(t *testing.T) {
	h := start(t)
	c := running(h, pc.ModeMotionAutomatic)
	c.send(&pc.MoveRelRequest{X: 1000, Y: 0, Angle: 90000}) // 1 m ahead, then a quarter turn left
	c.after(0.5)                                            // IpoTransVel 1000 mm/s: half way
	p := expectPose(t, c, 500, 0, 0, "after 0.5 s")
	if p.VelTrans != 1000 || p.VelRot != 0 {
		t.Errorf("velocity %g mm/s %g rad/s, want 1000, 0", p.VelTrans, p.VelRot)
	}
	s := c.status()
	if s.TargetReached != pc.Off || s.CmdX != 1000 || s.CmdAngle != 90000 || s.PlannerState != pc.PlannerPathFound {
		t.Errorf("moving: reached %d, commanded (%d, %d), planner %d", s.TargetReached, s.CmdX, s.CmdAngle, s.PlannerState)
	}
	c.after(1.0 + 0.5*math.Pi/0.6) // the rest of the line, then pi/2 at IpoRotVel 0.6 rad/s
	p = expectPose(t, c, 1000, 0, math.Pi/2, "at the end")
	if p.VelTrans != 0 || p.VelRot != 0 {
		t.Errorf("still moving: %g %g", p.VelTrans, p.VelRot)
	}
	s = c.status()
	if s.TargetReached != pc.On || s.EstX != 1000 || s.EstAngle != 90000 || s.CmdX != 1000 || s.PlannerState != pc.PlannerStandby {
		t.Errorf("after the move: reached %d est (%d, %d) cmd %d planner %d", s.TargetReached, s.EstX, s.EstAngle, s.CmdX, s.PlannerState)
	}
}

func TestMoveAbsTurnsFirstThenDrivesStraight(t *testing.T) {
	h := start(t)
	c := running(h, pc.ModeMotionAutomatic)
	c.send(&pc.MoveAbsRequest{X: 0, Y: 1200, Angle: 0})
	c.after(1)
	expectPose(t, c, 0, 0, 0.6, "turning on the spot") // E-MOT-007 reading: turn towards the target first
	c.after(0.5*math.Pi/0.6 - 1 + 0.6)
	expectPose(t, c, 0, 600, math.Pi/2, "on the line")
	c.after(100)
	expectPose(t, c, 0, 1200, 0, "at the target")
	// MOVE_ABS is in world coordinates: from (0, 1200) to (-500, 1200, 180 deg)
	c.send(&pc.MoveAbsRequest{X: -500, Y: 1200, Angle: 180000})
	c.after(100)
	expectPose(t, c, -500, 1200, math.Pi, "second target")
}

func TestNewMovePreemptsAndBreakHalts(t *testing.T) {
	h := start(t)
	c := running(h, pc.ModeMotionAutomatic)
	c.send(&pc.MoveRelRequest{X: 2000})
	c.after(0.5)
	c.send(&pc.BreakRequest{}) // E-MOT-005: halts at once, keeps the command
	c.after(5)
	expectPose(t, c, 500, 0, 0, "breaked")
	c.send(&pc.MoveRelRequest{X: 100}) // refused in Breaked (E-SRV-005)
	c.send(&pc.ContinueRequest{})
	c.after(0.5)
	expectPose(t, c, 1000, 0, 0, "continued")
	c.send(&pc.MoveRelRequest{X: 0, Y: 0, Angle: -90000}) // preempts: the rest of the 2 m is dropped
	c.after(10)
	expectPose(t, c, 1000, 0, -math.Pi/2, "after the preempting move")
	c.send(&pc.MoveRelRequest{X: 3000})
	c.after(1)
	c.send(&pc.StopRequest{})
	c.after(10)
	p := expectPose(t, c, 1000, -1000, -math.Pi/2, "stopped")
	if s := c.status(); s.OperationState != pc.StOpReady || s.TargetReached != pc.Off || p.VelTrans != 0 {
		t.Errorf("after STOP: state %d reached %d", s.OperationState, s.TargetReached)
	}
}

func TestMovePathFollowsTheFrames(t *testing.T) {
	h := start(t)
	c := running(h, pc.ModeMotionAutomatic)
	c.send(&pc.MovePathRequest{Frames: []pc.Frame{{X: 1000, Y: 0, Angle: 45000}, {X: 1000, Y: 1000, Angle: 180000}}})
	c.after(1)
	expectPose(t, c, 1000, 0, 0, "first frame, its angle not used (E-MOT-007)")
	c.after(100)
	expectPose(t, c, 1000, 1000, math.Pi, "last frame")
}

const stationRoadmap = `<?xml version="1.0"?>
<roadmap Version="1.0">
  <stations>
    <station id="a" name="A"><point x="0" y="0"/></station>
    <station id="b" name="B"><point x="1000" y="0"/></station>
    <station id="c" name="C" angle="90"><point x="1000" y="1000"/></station>
    <station id="d"><point x="5000" y="5000"/></station>
  </stations>
  <edges>
    <edge startstation="a" endstation="b"><points/></edge>
    <edge startstation="c" endstation="b"/>
    <edge startstation="a" endstation="c"><points><point x="-3000" y="0"/><point x="-3000" y="1000"/></points></edge>
    <edge startstation="d" endstation="c"><point x="5000" y="1000"/></edge>
  </edges>
</roadmap>`

func TestMoveToStationTakesTheShortestWay(t *testing.T) {
	h := start(t)
	c := running(h, pc.ModeMotionAutomatic)
	c.send(&pc.SetRoadmapRequest{Name: "test.rm", XML: stationRoadmap}, &pc.MoveToStationRequest{Station: "C"})
	c.after(1)
	expectPose(t, c, 1000, 0, 0, "at B, not on the detour over x = -3000") // a -> b -> c (edge c-b backwards)
	c.after(100)
	expectPose(t, c, 1000, 1000, math.Pi/2, "at C with its angle")
	c.send(&pc.MoveToStationRequest{Station: "d"}) // by id when no name matches (E-SRV-012)
	c.after(1000)
	expectPose(t, c, 5000, 5000, 0, "at d")
	c.send(&pc.MoveToStationRequest{Station: "Z"}) // unknown: refused, nothing moves
	c.after(10)
	expectPose(t, c, 5000, 5000, 0, "after an unknown station")
}

func TestVelocityModeKeepsTheVelocity(t *testing.T) {
	h := start(t)
	c := running(h, pc.ModeMotionVel)
	c.send(&pc.MoveVelWheelRequest{VelRight: 300, VelLeft: 300})
	c.after(2)
	expectPose(t, c, 600, 0, 0, "2 s at 300 mm/s")
	c.after(100) // no watchdog configured (E-PAR-018 alternative reading): still driving
	expectPose(t, c, 30600, 0, 0, "102 s at 300 mm/s")
	// an arc: 200 mm/s and 500 mrad/s (E-REP-005) is a circle of 400 mm radius
	c.send(&pc.MoveVelRequest{VelTrans: 200, VelRot: 500})
	c.after(1)
	p := expectPose(t, c, 30600+400*math.Sin(0.5), 400*(1-math.Cos(0.5)), 0.5, "1 s on the arc")
	if s := c.status(); s.VelTrans != 200 || s.VelRot != 500 || p.VelRot != 0.5 {
		t.Errorf("status velocities %d mm/s %d mrad/s, position %g rad/s", s.VelTrans, s.VelRot, p.VelRot)
	}
	// E-PAR-023: limited to MaxTransVel 1500 mm/s, wheel ratio kept
	c.send(&pc.MoveVelWheelRequest{VelRight: 6000, VelLeft: 6000})
	if v := c.position().VelTrans; v != 1500 {
		t.Errorf("limited to %g mm/s", v)
	}
	c.send(&pc.MoveVelRequest{}) // stop
}

func TestVelocityWatchdogWhenConfigured(t *testing.T) {
	h := startWith(t, model.Options{VelWatchdog: 0.5}, nil)
	c := running(h, pc.ModeMotionVel)
	c.send(&pc.MoveVelWheelRequest{VelRight: 300, VelLeft: 300})
	c.after(5)
	expectPose(t, c, 150, 0, 0, "stopped by the 0.5 s watchdog")
}

func TestJoysoftDecays(t *testing.T) {
	h := start(t)
	c := running(h, pc.ModeMotionJoysoft)
	c.send(&pc.MoveVelWheelRequest{VelRight: 300, VelLeft: 300}) // JOYSOFT takes only MOVE_VEL (guide 4.3)
	c.send(&pc.MoveVelRequest{VelTrans: 100})
	c.after(1.5)
	expectPose(t, c, 150, 0, 0, "1.5 s at 100 mm/s")
	c.after(10) // JoySoftVelTimeout 2000 ms (E-PAR-019): at rest after 2 s
	expectPose(t, c, 200, 0, 0, "decayed after 2 s")
}

func TestModesIgnoreForeignMoves(t *testing.T) {
	for mode, moves := range map[pc.MotionMode][]pc.Telegram{
		pc.ModeMotionNo:        {&pc.MoveVelRequest{VelTrans: 100}, &pc.MoveRelRequest{X: 100}},
		pc.ModeMotionAutomatic: {&pc.MoveVelRequest{VelTrans: 100}, &pc.MoveVelWheelRequest{VelRight: 100, VelLeft: 100}},
		pc.ModeMotionVel:       {&pc.MoveRelRequest{X: 100}, &pc.MoveAbsRequest{X: 100}},
		pc.ModeMotionProgram:   {&pc.MoveVelRequest{VelTrans: 100}, &pc.MoveAbsRequest{X: 100}},
	} {
		h := start(t)
		c := running(h, mode)
		c.send(moves...)
		c.after(5)
		expectPose(t, c, 0, 0, 0, "foreign moves in mode "+pc.Dump(&pc.SetModeRequest{Mode: mode}))
	}
	// and no move outside Running (Ready)
	h := start(t)
	c := h.dial(h.ports[0])
	c.send(&pc.ConnectToPltfRequest{}, &pc.InitPltfRequest{}, &pc.SetModeRequest{Mode: pc.ModeMotionVel},
		&pc.MoveVelRequest{VelTrans: 100})
	c.after(5)
	expectPose(t, c, 0, 0, 0, "a move in Ready")
}

func TestSetFramePlacesThePlatform(t *testing.T) {
	h := start(t)
	c := h.dial(h.ports[0])
	c.send(&pc.SetFrmPltfRequest{X: 1500, Y: -250, Angle: 90000})
	p := expectPose(t, c, 1500, -250, math.Pi/2, "after SET_FRM_PLTF")
	if p.Angle != math.Pi/2 {
		t.Errorf("angle %v, not exactly pi/2", p.Angle)
	}
	// far away: the INT fields are held to their range, every reply stays encodable
	c.send(&pc.SetFrmPltfRequest{X: math.MaxInt32, Y: math.MinInt32}, &pc.ConnectToPltfRequest{},
		&pc.InitPltfRequest{}, &pc.SetModeRequest{Mode: pc.ModeMotionAutomatic}, &pc.StartRequest{},
		&pc.MoveRelRequest{X: math.MaxInt32, Y: math.MaxInt32})
	c.after(1e6)
	if s := c.status(); s.EstX != math.MaxInt32 || s.CmdX != math.MaxInt32 || s.CmdY != -1 {
		t.Errorf("far away: est x %d, cmd (%d, %d)", s.EstX, s.CmdX, s.CmdY)
	}
}
