package model

// CMD_MOVE_TO_STATION (guide 4.3: "The shortest path on the roadmap from the current platform position to the
// target station is calculated. Following the command CMD_MOVE_PATH is executed"; E-SRV-012, E-XML-003).
//
// Rules: the station is found by name, then by id; an unknown one is refused. The route starts at the station
// nearest the current pose (the platform drives there first), then follows the shortest way over the
// undirected edges and their intermediate points (a <points> wrapper or bare <point> children) to the target,
// and ends with the target station's angle (degrees, absent 0: E-XML-007).

import (
	"container/heap"
	"errors"
	"math"
	"strconv"

	pc "platformctrl"
)

type rmPoint struct {
	X string `xml:"x,attr"`
	Y string `xml:"y,attr"`
}

type rmStation struct {
	ID    string  `xml:"id,attr"`
	Name  string  `xml:"name,attr"`
	Angle string  `xml:"angle,attr"`
	Point rmPoint `xml:"point"`
}

type rmEdge struct {
	Start   string    `xml:"startstation,attr"`
	End     string    `xml:"endstation,attr"`
	Wrapped []rmPoint `xml:"points>point"`
	Bare    []rmPoint `xml:"point"`
}

type rmDoc struct {
	Stations []rmStation `xml:"stations>station"`
	Edges    []rmEdge    `xml:"edges>edge"`
}

func (p rmPoint) pose() (Pose, error) {
	x, err1 := strconv.ParseFloat(p.X, 64)
	y, err2 := strconv.ParseFloat(p.Y, 64)
	if err1 != nil || err2 != nil || math.IsInf(x, 0) || math.IsInf(y, 0) {
		return Pose{}, errors.New("a point that is not two numbers")
	}
	return Pose{X: x, Y: y}, nil
}

// graph is the roadmap as stations (by index) and undirected edges with their inner points.
type graph struct {
	at    []Pose         // station positions, angle = the station's angle
	index map[string]int // id -> station
	name  map[string]int // name -> station (first of a name)
	adj   map[int][]hop  // station -> edges leaving it
}

type hop struct {
	to     int
	points []Pose // inner points in the direction of travel
	length float64
}

func parseRoadmap(doc []byte) (*graph, error) {
	var rm rmDoc
	if err := newDecoder(doc).Decode(&rm); err != nil {
		return nil, err
	}
	g := &graph{index: map[string]int{}, name: map[string]int{}, adj: map[int][]hop{}}
	for i, s := range rm.Stations {
		pos, err := s.Point.pose()
		if err != nil {
			return nil, errors.New("station " + s.ID + ": " + err.Error())
		}
		if s.Angle != "" {
			deg, err := strconv.ParseFloat(s.Angle, 64)
			if err != nil {
				return nil, errors.New("station " + s.ID + ": an angle that is not a number")
			}
			pos.Th = Normalize(deg * math.Pi / 180)
		}
		g.at = append(g.at, pos)
		g.index[s.ID] = i
		if _, dup := g.name[s.Name]; !dup && s.Name != "" {
			g.name[s.Name] = i
		}
	}
	for _, e := range rm.Edges {
		a, ok1 := g.index[e.Start]
		b, ok2 := g.index[e.End]
		if !ok1 || !ok2 {
			return nil, errors.New("an edge to an undefined station")
		}
		var inner []Pose
		for _, p := range append(e.Wrapped, e.Bare...) {
			pos, err := p.pose()
			if err != nil {
				return nil, err
			}
			inner = append(inner, pos)
		}
		length, prev := 0.0, g.at[a]
		for _, p := range append(inner, g.at[b]) {
			length += math.Hypot(p.X-prev.X, p.Y-prev.Y)
			prev = p
		}
		back := make([]Pose, len(inner))
		for i, p := range inner {
			back[len(inner)-1-i] = p
		}
		g.adj[a] = append(g.adj[a], hop{b, inner, length})
		g.adj[b] = append(g.adj[b], hop{a, back, length})
	}
	return g, nil
}

// route is the waypoints from the station nearest from to station target (Dijkstra).
func (g *graph) route(from Pose, target int) ([]Pose, bool) {
	start, best := -1, math.Inf(1)
	for i, p := range g.at {
		if d := math.Hypot(p.X-from.X, p.Y-from.Y); d < best {
			start, best = i, d
		}
	}
	dist := map[int]float64{start: 0}
	prev := map[int]int{}
	via := map[int][]Pose{}
	q := &queue{{start, 0}}
	for q.Len() > 0 {
		it := heap.Pop(q).(item)
		if it.d > dist[it.n] {
			continue
		}
		if it.n == target {
			break
		}
		for _, h := range g.adj[it.n] {
			d := it.d + h.length
			if old, seen := dist[h.to]; seen && d >= old {
				continue
			}
			dist[h.to], prev[h.to], via[h.to] = d, it.n, h.points
			heap.Push(q, item{h.to, d})
		}
	}
	if _, ok := dist[target]; !ok {
		return nil, false
	}
	var rev [][]Pose
	for n := target; n != start; n = prev[n] {
		leg := append(append([]Pose{}, via[n]...), g.at[n])
		rev = append(rev, leg)
	}
	out := []Pose{g.at[start]}
	for i := len(rev) - 1; i >= 0; i-- {
		out = append(out, rev[i]...)
	}
	return out, true
}

type item struct {
	n int
	d float64
}

type queue []item

func (q queue) Len() int           { return len(q) }
func (q queue) Less(i, j int) bool { return q[i].d < q[j].d }
func (q queue) Swap(i, j int)      { q[i], q[j] = q[j], q[i] }
func (q *queue) Push(x any)        { *q = append(*q, x.(item)) }
func (q *queue) Pop() any          { old := *q; it := old[len(old)-1]; *q = old[:len(old)-1]; return it }

func moveToStation(p *Platform, t pc.Telegram) string {
	name := t.(*pc.MoveToStationRequest).Station
	rm := p.Docs.Active[RoadmapDoc]
	if !rm.Active {
		return "no active roadmap"
	}
	g, err := parseRoadmap(bytesOf(rm.XML))
	if err != nil {
		return "the roadmap cannot be read: " + err.Error()
	}
	target, ok := g.name[name]
	if !ok {
		if target, ok = g.index[name]; !ok {
			return "unknown station " + strconv.Quote(name)
		}
	}
	points, ok := g.route(p.Drive.Pose, target)
	if !ok {
		return "no way on the roadmap to station " + strconv.Quote(name)
	}
	p.moveTo(points)
	return ""
}
