// emulator: a small PlatformCtrl emulator (issue 17), a second implementation of the protocol written from spec/.
//
//	emulator [--ports 10000,10002] [--host 127.0.0.1] [--reply-delay-ms 2] [--time-scale 1] [--seed N]
//	         [--data-dir DIR] [--vel-watchdog-ms 0] [--stall-timeout-s 5]
//
// It logs "emulator: server started at port N" once per port, in port order, like the reference server.
package main

import (
	"bufio"
	"errors"
	"flag"
	"fmt"
	"io"
	"os"
	"os/signal"
	"path/filepath"
	"strconv"
	"strings"
	"syscall"
	"time"

	"pltf/emulator/internal/model"
	"pltf/emulator/internal/server"
)

type config struct {
	host        string
	ports       []int
	replyDelay  time.Duration
	timeScale   float64
	seed        int64
	dataDir     string
	velWatchdog time.Duration
	stall       time.Duration
}

func parseArgs(args []string, stderr io.Writer) (config, error) {
	c := config{}
	fs := flag.NewFlagSet("emulator", flag.ContinueOnError)
	fs.SetOutput(io.Discard) // errors are one line (run prints them); --help prints the flags
	ports := fs.String("ports", "10000,10002", "the two ports A,B (0: an ephemeral port)")
	fs.StringVar(&c.host, "host", "127.0.0.1", "address to listen on")
	delay := fs.Float64("reply-delay-ms", 2, "each reply is written this long after its request was handled")
	fs.Float64Var(&c.timeScale, "time-scale", 1, "simulated seconds per wall-clock second")
	fs.Int64Var(&c.seed, "seed", 0, "accepted for the launchers; the ideal emulator draws no random numbers")
	fs.StringVar(&c.dataDir, "data-dir", "", "the platform's files (Map/PltfMap.map, Roadmap/PltfRoadmap.rm, "+
		"Program/PltfProgram.xml, StartupPosition.dat); default: an empty disk in memory")
	watchdog := fs.Float64("vel-watchdog-ms", 0, "velocity watchdog of MODE_MOTION_VEL (0: none, E-PAR-018 alternative)")
	stall := fs.Float64("stall-timeout-s", 5, "a partial frame stalled this long closes its connection (E-SRV-014)")
	if err := fs.Parse(args); err != nil {
		if errors.Is(err, flag.ErrHelp) {
			fmt.Fprintln(stderr, "usage: emulator [flags]  (a PlatformCtrl emulator, see emulator/README.md)")
			fs.SetOutput(stderr)
			fs.PrintDefaults()
		}
		return c, err
	}
	if fs.NArg() > 0 {
		return c, fmt.Errorf("unexpected argument %q", fs.Arg(0))
	}
	for _, part := range strings.Split(*ports, ",") {
		n, err := strconv.Atoi(strings.TrimSpace(part))
		if err != nil || n < 0 || n > 65535 {
			return c, fmt.Errorf("--ports: %q is not a port number", part)
		}
		c.ports = append(c.ports, n)
	}
	if len(c.ports) != 2 {
		return c, errors.New("--ports: expected two ports A,B")
	}
	if *delay < 0 || *watchdog < 0 || *stall < 0 || !(c.timeScale > 0) {
		return c, errors.New("--reply-delay-ms, --vel-watchdog-ms, --stall-timeout-s must be >= 0, --time-scale > 0")
	}
	c.replyDelay = time.Duration(*delay * float64(time.Millisecond))
	c.velWatchdog = time.Duration(*watchdog * float64(time.Millisecond))
	c.stall = time.Duration(*stall * float64(time.Second))
	return c, nil
}

// startPose reads StartupPosition.dat: "x y angle" (mm, mm, rad); '#' starts a comment line.
func startPose(path string) (model.Pose, error) {
	f, err := os.Open(path)
	if err != nil {
		return model.Pose{}, err
	}
	defer f.Close()
	sc := bufio.NewScanner(f)
	for sc.Scan() {
		line := strings.TrimSpace(sc.Text())
		if line == "" || strings.HasPrefix(line, "#") {
			continue
		}
		var x, y, a float64
		if _, err := fmt.Sscan(line, &x, &y, &a); err != nil {
			return model.Pose{}, fmt.Errorf("%s: expected \"x y angle\": %v", path, err)
		}
		return model.Pose{X: x, Y: y, Th: model.Normalize(a)}, nil
	}
	return model.Pose{}, fmt.Errorf("%s: no pose", path)
}

// run is main without os.Exit: the exit status.
func run(args []string, stdout, stderr io.Writer, stop <-chan os.Signal) int {
	c, err := parseArgs(args, stderr)
	if err != nil {
		if errors.Is(err, flag.ErrHelp) {
			return 0
		}
		fmt.Fprintln(stderr, "emulator:", err)
		return 2
	}
	logf := func(format string, a ...any) { fmt.Fprintf(stdout, format+"\n", a...) }
	opts := model.Options{VelWatchdog: c.velWatchdog.Seconds(), Logf: func(line string) { logf("%s", line) }}
	if c.dataDir != "" {
		opts.Disk = dirDisk(c.dataDir)
		pose, err := startPose(filepath.Join(c.dataDir, "StartupPosition.dat"))
		switch {
		case err == nil:
			opts.Start = pose
			logf("init pose read from StartupPosition.dat: %g %g %g", pose.X, pose.Y, pose.Th)
		case !errors.Is(err, os.ErrNotExist):
			fmt.Fprintln(stderr, "emulator:", err)
			return 2
		}
	}
	start := time.Now()
	srv := &server.Server{
		Platform:     model.New(opts),
		Clock:        func() float64 { return time.Since(start).Seconds() * c.timeScale },
		ReplyDelay:   c.replyDelay,
		StallTimeout: c.stall,
		Logf:         logf,
	}
	if err := srv.Listen(c.host, c.ports); err != nil {
		fmt.Fprintln(stderr, "emulator:", err)
		return 2
	}
	go func() {
		select {
		case sig := <-stop:
			logf("%s: the emulator stops", sig)
			srv.Shutdown()
		case <-srv.Done():
		}
	}()
	srv.Serve()
	return 0
}

func main() {
	stop := make(chan os.Signal, 1)
	signal.Notify(stop, syscall.SIGINT, syscall.SIGTERM)
	os.Exit(run(os.Args[1:], os.Stdout, os.Stderr, stop))
}
