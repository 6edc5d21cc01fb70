// Package model is the emulated platform: the state chart, motion modes, parameters, documents and status of
// PlatformCtrl (guide chapters 4 and 6), as plain objects. It is sans-IO: every request comes in with the
// simulated time `now` (seconds); nothing here touches a socket or a clock.
package model

import (
	"fmt"
	"math"
	"strings"

	"pltf/emulator/internal/ids"
	"pltf/emulator/internal/params"

	pc "platformctrl"
)

// Result is what a request leads to beyond the state change.
type Result struct {
	Reply pc.Telegram // nil: no reply (only GET_* are answered, E-CMD-013)
	Close bool        // CMD_CLOSE_SOCKET: close this connection
	Exit  bool        // CMD_EXIT: close everything and end the process (E-SRV-015)
}

// Options configure a platform at start-up (the emulator's stand-in for its parameter files).
type Options struct {
	Start Pose // StartupPosition.dat
	// VelWatchdog is the VEL mode's velocity watchdog in seconds; 0: none configured (E-PAR-018 alternative
	// reading "the velocity is kept until the next command"; VelWatchdogTime is then not offered, E-PAR-024).
	VelWatchdog float64
	Disk        Disk
	Logf        func(string) // each log line, as it happens (may be nil)
}

// Platform is the emulated PlatformCtrl.
type Platform struct {
	State  State
	Mode   pc.MotionMode
	Params *params.Store
	Docs   Documents
	Drive  *Drive

	now           float64 // simulated seconds of the last request
	targetReached bool
	watchdog      float64
	board         boards
	mapping       bool
	logs          []string // the last 32 log lines (GET_DEBUG_DATA protocol queue, E-SRV-017)
	logf          func(string)
}

// New is a platform at start-up: not connected, motion mode NO, standing at o.Start.
func New(o Options) *Platform {
	omit := []string{}
	if o.VelWatchdog <= 0 {
		omit = append(omit, "VelWatchdogTime")
	}
	p := &Platform{Mode: pc.ModeMotionNo, Params: params.NewStore(omit...), Drive: NewDrive(o.Start),
		watchdog: o.VelWatchdog, logf: o.Logf}
	if o.VelWatchdog > 0 {
		p.Params.SetDefault("VelWatchdogTime", math.Round(o.VelWatchdog*1000))
	}
	p.Docs.Disk = o.Disk
	if p.Docs.Disk == nil {
		p.Docs.Disk = MemDisk{}
	}
	p.board.listen = map[int32]bool{}
	for _, k := range []DocKind{MapDoc, RoadmapDoc, ProgramDoc} {
		if err := p.Docs.Load(k); err == nil {
			p.Logf("load %s: %s", k, docFiles[k])
		}
	}
	return p
}

// Logf records a log line with the simulated time. Control characters a peer smuggled in become '?', so
// no request can forge a line (such as the "server started at port N" the launchers read).
func (p *Platform) Logf(format string, args ...any) {
	line := strings.Map(func(r rune) rune {
		if r < 0x20 || r == 0x7f {
			return '?'
		}
		return r
	}, fmt.Sprintf("%.3f %s", p.now, fmt.Sprintf(format, args...)))
	p.logs = append(p.logs, line)
	if len(p.logs) > 32 {
		p.logs = p.logs[len(p.logs)-32:]
	}
	if p.logf != nil {
		p.logf(line)
	}
}

// Advance runs the simulation up to now (simulated seconds); earlier times change nothing.
func (p *Platform) Advance(now float64) {
	if now <= p.now {
		return
	}
	if p.Drive.Advance(now, now-p.now) {
		p.targetReached = true // the ideal drive ends exactly on its target (E-SRV-009, E-PAR-021)
		p.now = now
		p.Logf("target reached")
	}
	p.now = now
}

// Now is the simulated time of the last request.
func (p *Platform) Now() float64 { return p.now }

type handler func(p *Platform, t pc.Telegram) Result

// Handle takes one decoded request at simulated time now.
func (p *Platform) Handle(t pc.Telegram, now float64) Result {
	p.Advance(now)
	if h, ok := handlers[t.TelegramID()]; ok {
		return h(p, t)
	}
	p.Logf("%s accepted and ignored", t.TelegramName()) // E-CMD-012, E-SRV-013
	return Result{}
}

func (p *Platform) refuse(t pc.Telegram, why string) Result {
	p.Logf("%s refused: %s", t.TelegramName(), why)
	return Result{}
}

// chart applies an operation command through the chart table.
func chart(effect func(p *Platform)) handler {
	return func(p *Platform, t pc.Telegram) Result {
		to, ok := Next(p.State, t.TelegramID())
		if !ok {
			return p.refuse(t, "not allowed in state "+p.State.String())
		}
		from := p.State
		p.State = to
		if effect != nil {
			effect(p)
		}
		p.Logf("%s: %s -> %s", t.TelegramName(), from, to)
		return Result{}
	}
}

// halt ends every motion command at once (CMD_STOP, CMD_SHUTDOWN_PLTF, CMD_EXIT: E-MOT-005 ideal drives).
func halt(p *Platform) {
	p.Drive.Stop()
	p.Drive.Halted = false
}

func setMode(p *Platform, t pc.Telegram) Result {
	mode := t.(*pc.SetModeRequest).Mode
	if _, ok := Next(p.State, ids.SetMode); !ok {
		return p.refuse(t, "the motion mode changes only in state ready (guide 6.3)")
	}
	p.Mode = mode
	p.Logf("motion mode %d", mode)
	return Result{}
}

// move checks that the state and the motion mode take a move command (guide 4.2, 4.3; E-SRV-005).
func move(do func(p *Platform, t pc.Telegram) string) handler {
	return func(p *Platform, t pc.Telegram) Result {
		if p.State != Running {
			return p.refuse(t, "moves only in state running (E-SRV-005)")
		}
		if !moveModes[p.Mode][t.TelegramID()] {
			p.Logf("%s ignored in motion mode %d (guide 4.3)", t.TelegramName(), p.Mode)
			return Result{}
		}
		if why := do(p, t); why != "" {
			return p.refuse(t, why)
		}
		return Result{}
	}
}

// limits are the velocities a command may ask for (E-PAR-023: MaxTransVel mm/s, MaxRotVel rad/s).
func (p *Platform) limits() (float64, float64) {
	return p.Params.Value("MaxTransVel", 1500), p.Params.Value("MaxRotVel", 1.5)
}

// ipo are the speeds of a move (E-PAR-015: IpoTransVel, IpoRotVel, limited to the maxima).
func (p *Platform) ipo() (float64, float64) {
	vmax, wmax := p.limits()
	return math.Min(p.Params.Value("IpoTransVel", 1000), vmax), math.Min(p.Params.Value("IpoRotVel", 0.6), wmax)
}

func clamp(v, limit float64) float64 { return math.Max(-limit, math.Min(limit, v)) }

// velDeadline: JOYSOFT decays after JoySoftVelTimeout (E-PAR-019); VEL keeps the velocity unless a watchdog is
// configured (E-PAR-018: the emulator's default is the alternative reading, no watchdog).
func (p *Platform) velDeadline() float64 {
	if p.Mode == pc.ModeMotionJoysoft {
		return p.now + p.Params.Value("JoySoftVelTimeout", 2000)/1000
	}
	if p.watchdog > 0 {
		return p.now + p.watchdog
	}
	return math.Inf(1)
}

func moveVel(p *Platform, t pc.Telegram) string {
	r := t.(*pc.MoveVelRequest)
	vmax, wmax := p.limits()
	// guide 6.3 CMD_MOVE_VEL: rotational velocity in 1000*rad/s (E-REP-005: mrad/s)
	p.Drive.SetVelocity(clamp(float64(r.VelTrans), vmax), clamp(float64(r.VelRot)/1000, wmax), p.velDeadline())
	return ""
}

func moveVelWheel(p *Platform, t pc.Telegram) string {
	r := t.(*pc.MoveVelWheelRequest)
	vr, vl := float64(r.VelRight), float64(r.VelLeft)
	v, w := (vr+vl)/2, (vr-vl)/p.Params.Value("DistWheels", 430)
	vmax, wmax := p.limits()
	// E-PAR-023: limited so that the ratio of the two wheels is kept
	s := math.Min(1, math.Min(vmax/math.Max(math.Abs(v), 1e-12), wmax/math.Max(math.Abs(w), 1e-12)))
	p.Drive.SetVelocity(v*s, w*s, p.velDeadline())
	return ""
}

// frame converts an INT frame (mm, 1000*deg) into a Pose.
func frame(x, y, angle int32) Pose {
	return Pose{float64(x), float64(y), Normalize(float64(angle) / 1000 * math.Pi / 180)}
}

func (p *Platform) moveTo(points []Pose) {
	vt, wt := p.ipo()
	p.targetReached = false // E-SRV-009: a new move clears the flag
	p.Drive.MoveThrough(points, vt, wt)
}

func moveAbs(p *Platform, t pc.Telegram) string {
	r := t.(*pc.MoveAbsRequest)
	p.moveTo([]Pose{frame(r.X, r.Y, r.Angle)})
	return ""
}

func moveRel(p *Platform, t pc.Telegram) string {
	r := t.(*pc.MoveRelRequest)
	p.moveTo([]Pose{Compose(p.Drive.Pose, frame(r.X, r.Y, r.Angle))})
	return ""
}

// maxWaypoints bounds a path (E-MOT-014: a longer path is sampled evenly, keeping its last frame).
const maxWaypoints = 50000

func movePath(p *Platform, t pc.Telegram) string {
	frames := t.(*pc.MovePathRequest).Frames
	if len(frames) == 0 {
		return "a path without frames"
	}
	step := (len(frames) + maxWaypoints - 1) / maxWaypoints
	points := make([]Pose, 0, len(frames)/step+1)
	for i := 0; i < len(frames); i += step {
		points = append(points, frame(frames[i].X, frames[i].Y, frames[i].Angle))
	}
	if last := frames[len(frames)-1]; (len(frames)-1)%step != 0 {
		points = append(points, frame(last.X, last.Y, last.Angle))
	}
	p.moveTo(points)
	return ""
}

var handlers = map[uint8]handler{
	ids.ConnectToPltf: chart(nil),
	ids.ShutdownPltf:  chart(func(p *Platform) { halt(p); p.board.busDown() }), // E-SRV-003
	ids.InitPltf:      chart(func(p *Platform) { p.board.brake = [3]bool{} }),  // the self test releases the brakes (E-HW-005)
	ids.Start:         chart(nil),
	ids.Break:         chart(func(p *Platform) { p.Drive.Halted = true }), // halt, keep the command (E-MOT-005)
	ids.Continue:      chart(func(p *Platform) { p.Drive.Halted = false }),
	ids.Stop:          chart(halt),
	ids.SetMode:       setMode,
	ids.Exit:          exit,
	ids.CloseSocket:   func(p *Platform, t pc.Telegram) Result { p.Logf("close socket"); return Result{Close: true} },
	ids.GetStatus:     getStatus,
	ids.GetPosition:   getPosition,
	ids.MovePath:      move(movePath),
	ids.MoveToStation: move(moveToStation),
	ids.MoveAbs:       move(moveAbs),
	ids.MoveRel:       move(moveRel),
	ids.MoveVelWheel:  move(moveVelWheel),
	ids.MoveVel:       move(moveVel),
}
