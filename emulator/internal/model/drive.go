package model

// The ideal differential drive (guide 4.1 "Simulation"; E-MOT-011 alternative: an ideal simulation without noise).
//
// Rules:
//   - The pose is integrated exactly (circular arcs) between events; there is no control period, no noise and no
//     ramp: a commanded velocity holds at once, a halt is at once (E-MOT-005 / E-MOT-013 alternative "ideal drives").
//   - The estimate is the truth (no localization): CMD_SET_FRM_PLTF moves both.
//   - A move is a list of legs, each a turn on the spot or a straight line at constant speed (E-MOT-007: the
//     platform turns towards the target first and drives straight); its last leg ends exactly on the target.
//   - Time comes in as an argument (simulated seconds); nothing here reads a clock.

import "math"

// Pose is a platform frame: x, y in mm, th in rad counter-clockwise from the x axis, normalised to (-pi, pi].
type Pose struct{ X, Y, Th float64 }

// leg is one piece of a move: velocities held for dur seconds, then the pose is set to end.
type leg struct {
	v, w float64 // mm/s, rad/s
	dur  float64 // s
	end  Pose
}

// Drive is the platform body: its pose, the velocities it is driving and the legs of a move still ahead.
type Drive struct {
	Pose Pose
	V, W float64 // the velocities of a velocity command (mm/s, rad/s), held until changed or timed out
	// VelDeadline: simulated time at which a velocity command times out (JOYSOFT, or VEL with a watchdog); +Inf none.
	VelDeadline float64
	legs        []leg
	legDone     float64 // seconds of legs[0] already driven
	Halted      bool    // CMD_BREAK: nothing moves, the command is kept
}

// NewDrive stands at pose.
func NewDrive(p Pose) *Drive { return &Drive{Pose: p, VelDeadline: math.Inf(1)} }

// Moving is true while a move has legs left.
func (d *Drive) Moving() bool { return len(d.legs) > 0 }

// Target is the end frame of the move being driven.
func (d *Drive) Target() (Pose, bool) {
	if len(d.legs) == 0 {
		return Pose{}, false
	}
	return d.legs[len(d.legs)-1].end, true
}

// Velocity is what the platform drives right now (mm/s, rad/s).
func (d *Drive) Velocity() (float64, float64) {
	switch {
	case d.Halted:
		return 0, 0
	case len(d.legs) > 0:
		return d.legs[0].v, d.legs[0].w
	}
	return d.V, d.W
}

// Stop ends every command: no legs, no velocity.
func (d *Drive) Stop() {
	d.legs, d.legDone = nil, 0
	d.V, d.W, d.VelDeadline = 0, 0, math.Inf(1)
}

// SetVelocity starts a velocity command that holds until deadline (+Inf: until the next command).
func (d *Drive) SetVelocity(v, w, deadline float64) {
	d.legs, d.legDone = nil, 0
	d.V, d.W, d.VelDeadline = v, w, deadline
}

// MoveThrough plans a move through the waypoints' positions, turning to the last waypoint's angle at the end
// (E-MOT-007: inner angles are not used). vt (mm/s) and wt (rad/s) are the speeds of the legs.
func (d *Drive) MoveThrough(points []Pose, vt, wt float64) {
	d.V, d.W, d.VelDeadline = 0, 0, math.Inf(1)
	d.legs, d.legDone = nil, 0
	at := d.Pose
	for _, p := range points {
		dx, dy := p.X-at.X, p.Y-at.Y
		if dist := math.Hypot(dx, dy); dist > 1e-6 {
			heading := math.Atan2(dy, dx)
			at = d.turn(at, heading, wt)
			end := Pose{p.X, p.Y, at.Th}
			d.legs = append(d.legs, leg{v: vt, dur: dist / vt, end: end})
			at = end
		}
	}
	final := points[len(points)-1]
	d.turn(at, Normalize(final.Th), wt)
	if len(d.legs) == 0 { // already there: one empty leg, so the move still ends (and reports reached) in order
		d.legs = append(d.legs, leg{end: Pose{final.X, final.Y, Normalize(final.Th)}})
	}
	d.legs[len(d.legs)-1].end = Pose{final.X, final.Y, Normalize(final.Th)}
}

// turn appends a turn on the spot from at to heading (the shorter way) and returns the pose after it.
func (d *Drive) turn(at Pose, heading, wt float64) Pose {
	delta := Normalize(heading - at.Th)
	end := Pose{at.X, at.Y, Normalize(heading)}
	if math.Abs(delta) > 1e-9 {
		d.legs = append(d.legs, leg{w: math.Copysign(wt, delta), dur: math.Abs(delta) / wt, end: end})
	}
	return end
}

// Advance drives for dt seconds, from simulated time now-dt to now. It returns true when a move ended in it.
func (d *Drive) Advance(now, dt float64) bool {
	if d.Halted || dt <= 0 {
		return false
	}
	ended := false
	for dt > 0 && len(d.legs) > 0 {
		l := &d.legs[0]
		left := l.dur - d.legDone
		if dt < left {
			d.Pose = integrate(d.Pose, l.v, l.w, dt)
			d.legDone += dt
			return false
		}
		d.Pose = l.end // the leg's exact end, no rounding drift
		dt -= left
		d.legs, d.legDone = d.legs[1:], 0
		ended = len(d.legs) == 0
	}
	if dt > 0 && (d.V != 0 || d.W != 0) {
		start := now - dt
		if run := math.Min(dt, d.VelDeadline-start); run > 0 {
			d.Pose = integrate(d.Pose, d.V, d.W, run)
		}
		if now >= d.VelDeadline {
			d.V, d.W, d.VelDeadline = 0, 0, math.Inf(1)
		}
	}
	return ended
}

// integrate moves p along the arc of (v, w) for dt seconds.
func integrate(p Pose, v, w, dt float64) Pose {
	th := p.Th + w*dt
	if math.Abs(w) < 1e-12 {
		return Pose{p.X + v*dt*math.Cos(p.Th), p.Y + v*dt*math.Sin(p.Th), Normalize(th)}
	}
	r := v / w
	return Pose{p.X + r*(math.Sin(th)-math.Sin(p.Th)), p.Y - r*(math.Cos(th)-math.Cos(p.Th)), Normalize(th)}
}

// Normalize brings an angle into (-pi, pi].
func Normalize(a float64) float64 {
	a = math.Mod(a, 2*math.Pi)
	if a <= -math.Pi {
		a += 2 * math.Pi
	} else if a > math.Pi {
		a -= 2 * math.Pi
	}
	return a
}

// Compose is p (+) r: the frame r, given in p's coordinates, in world coordinates (CMD_MOVE_REL).
func Compose(p, r Pose) Pose {
	c, s := math.Cos(p.Th), math.Sin(p.Th)
	return Pose{p.X + c*r.X - s*r.Y, p.Y + s*r.X + c*r.Y, Normalize(p.Th + r.Th)}
}

// Waypoints are the positions the move still drives to (the ends of its straight legs) and its end frame.
func (d *Drive) Waypoints() []Pose {
	var out []Pose
	for i, l := range d.legs {
		if l.v != 0 || i == len(d.legs)-1 {
			out = append(out, l.end)
		}
	}
	return out
}
