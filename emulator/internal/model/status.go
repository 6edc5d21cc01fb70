package model

// The status replies: CMD_GET_STATUS, CMD_GET_POSITION, CMD_GET_DEBUG_DATA (guide 6.4).
//
// Rules:
//   - Positions are mm, INT angles 1000*deg, velocities mm/s and 1/1000 rad/s (E-REP-005); GET_POSITION's
//     DOUBLE angle is rad and its velocities mm/s and rad/s (E-REP-012). INT values are rounded and held to
//     the INT range, so no pose, however far, makes a reply unencodable.
//   - The commanded frame is the end frame of the move being driven, else the estimated pose (E-SRV-008).
//   - Boards: with the bus down every board is absent (status -1, readings 0, E-HW-003); with it up the IO,
//     relay, motor and ultrasonic boards are present and well (status 0; 0x01 until CMD_INIT_PLTF, motors
//     0x10 while a brake is engaged, ultrasonic 0x10 while measuring: E-HW-006), radar and gyro are absent
//     (E-HW-018). The battery reads a constant 25000 mV and the boards 25 degC. There is no laser scanner,
//     no joystick and no localization: scan, lines, covariances and the other observations are empty or 0.

import (
	"math"
	"strings"

	pc "platformctrl"
)

const absent = -1

// i32 rounds and holds a value to the INT range.
func i32(v float64) int32 {
	switch {
	case math.IsNaN(v):
		return 0
	case v >= math.MaxInt32:
		return math.MaxInt32
	case v <= math.MinInt32:
		return math.MinInt32
	}
	return int32(math.Round(v))
}

// mdeg is an angle in rad as 1000*deg.
func mdeg(th float64) int32 { return i32(th * 180 / math.Pi * 1000) }

func flag(b bool) pc.Flag {
	if b {
		return pc.On
	}
	return pc.Off
}

// boardStatus is a present board's status word (E-HW-006), or -1 with the bus down.
func (p *Platform) boardStatus(extra int32) int32 {
	switch {
	case !p.State.BusUp():
		return absent
	case !p.State.Initialized():
		return 0x01 | extra
	}
	return extra
}

func getStatus(p *Platform, t pc.Telegram) Result {
	pose := p.Drive.Pose
	cmd := pose
	if target, ok := p.Drive.Target(); ok {
		cmd = target
	}
	v, w := p.Drive.Velocity()
	up := p.State.BusUp()
	r := &pc.GetStatusReply{
		CmdX: i32(cmd.X), CmdY: i32(cmd.Y), CmdAngle: mdeg(cmd.Th),
		EstX: i32(pose.X), EstY: i32(pose.Y), EstAngle: mdeg(pose.Th),
		VelTrans: i32(v), VelRot: mrad(w),
		RelayStatus: p.boardStatus(0), IOStatus: p.boardStatus(0),
		MotorRightStatus: p.boardStatus(p.brakeBit(1)), MotorLeftStatus: p.boardStatus(p.brakeBit(2)),
		UsStatus: p.boardStatus(0), RadarStatus: absent, GyroStatus: absent,
		Initialized: flag(p.State.Initialized()), TargetReached: flag(p.targetReached),
		MotionMode: p.Mode, OperationState: p.State.Reported(), EmergencyState: pc.StEmNotActive,
		PlannerState: pc.PlannerStandby,
		Timestamp:    int32(int64(p.now*1000) % (1 << 31)), // E-REP-010: ms since start, wrapping at 2^31
		Siren:        flag(p.Params.Value("SirenEnabled", 0) != 0),
		Flashlight:   flag(p.Params.Value("FlashlightEnabled", 0) != 0),
		HeadPosition: p.board.head,
	}
	if p.Drive.Moving() && !p.Drive.Halted {
		r.PlannerState = pc.PlannerPathFound // E-MOT-006: a path is being driven
	}
	if up {
		r.IOBatteryVoltage, r.MotorRightTemp, r.MotorLeftTemp = 25000, 25, 25
		r.IODigitalOut = int32(p.board.digout)
		if p.board.usOn {
			r.UsStatus |= 0x10
			for i := range r.UsDistance { // E-HW-012: no echo in the empty world: the maximum range, 3000 mm
				if p.board.usMask&(1<<uint(i)) != 0 {
					r.UsDistance[i] = 3000
				}
			}
		}
	}
	return Result{Reply: r}
}

// brakeBit is 0x10 while motor m's brake is engaged: from power-up until CMD_INIT_PLTF releases it (E-HW-005),
// and after CMD_SET_BRAKE engaged it.
func (p *Platform) brakeBit(m int) int32 {
	if !p.State.Initialized() || p.board.brake[m] {
		return 0x10
	}
	return 0
}

func getPosition(p *Platform, t pc.Telegram) Result {
	pose := p.Drive.Pose
	v, w := p.Drive.Velocity()
	return Result{Reply: &pc.GetPositionReply{X: i32(pose.X), Y: i32(pose.Y), Angle: pose.Th, VelTrans: v, VelRot: w}}
}

func getDebugData(p *Platform, t pc.Telegram) Result {
	queue := make([]pc.ProtocolEntry, len(p.logs))
	for i, line := range p.logs {
		queue[i] = pc.ProtocolEntry{Entry: strings.Map(func(r rune) rune {
			if r > 255 {
				return '?' // E-SRV-017: non-Latin-1 characters as '?'
			}
			return r
		}, line)}
	}
	safe := i32(p.Params.Value("MaxTransVel", 1500)) // E-SRV-017: no sensor restricts the speed
	return Result{Reply: &pc.GetDebugDataReply{
		MappingMode: flag(p.mapping), ProtocolQueue: queue,
		SafeVelLaserForward: safe, SafeVelLaserBackward: safe, SafeVelUsForward: safe, SafeVelUsBackward: safe,
		SafeVelOptocoupler: safe,
	}}
}
