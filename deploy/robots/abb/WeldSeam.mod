MODULE WeldSeam
    ! weldseam text link, ABB (RAPID): capture, plan, weld.
    !
    ! A starting point for a robot programmer (see ROBOTS.md beside
    ! PROTOCOL.md). The robot stands at the capture pose, asks the daemon
    ! to trigger the camera and plan, pulls every waypoint into an array,
    ! then welds: approach, the seam at weld speed, retract. An error line
    ! stops with its reason on the FlexPendant. Needs the socket option
    ! (PC Interface / Socket Messaging).
    !
    ! Every reply fits a RAPID string of 80 characters; its numbers are
    ! plain num literals for StrToVal. Waypoints are torch poses in the
    ! base frame: mm and a quaternion q1..q4.

    CONST string DAEMON_IP := "192.168.1.10";
    CONST num DAEMON_PORT := 7303;
    CONST string JOINT := "lap";
    ! The most waypoint lines one plan may bring here.
    CONST num MAX_POINTS := 200;

    PERS tooldata tTorch := [TRUE, [[0, 0, 350], [1, 0, 0, 0]], [3, [0, 0, 100], [1, 0, 0, 0], 0, 0, 0]];
    VAR socketdev sock;
    VAR robtarget points{MAX_POINTS};
    VAR num kinds{MAX_POINTS};
    VAR num count;

    PROC main()
        VAR robtarget capture;
        VAR string reply;
        VAR num fields{10};
        VAR num n;

        SocketCreate sock;
        SocketConnect sock, DAEMON_IP, DAEMON_PORT \Time:=2;
        Ask "HELLO,abb", reply;
        CheckOk reply;

        ! The flange pose at capture; the robot stands still until the reply.
        capture := CRobT(\Tool:=tool0 \WObj:=wobj0);
        Ask "TRIGGER," + JOINT + "," + NumToStr(capture.trans.x, 2) + "," + NumToStr(capture.trans.y, 2) + ","
            + NumToStr(capture.trans.z, 2) + "," + NumToStr(capture.rot.q1, 6) + "," + NumToStr(capture.rot.q2, 6)
            + "," + NumToStr(capture.rot.q3, 6) + "," + NumToStr(capture.rot.q4, 6), reply;
        CheckOk reply;
        ! An ok line: 0,seams,lines.
        n := Split(reply, fields);
        count := fields{3};
        IF count > MAX_POINTS THEN
            Ask "DROP", reply;
            ErrWrite "weldseam", "the plan has more waypoints than MAX_POINTS";
            Stop;
        ENDIF

        ! Pull: kind,seam,remaining,x,y,z,q1,q2,q3,q4.
        FOR i FROM 1 TO count DO
            Ask "NEXT", reply;
            CheckOk reply;
            n := Split(reply, fields);
            kinds{i} := fields{1};
            points{i} := CRobT(\Tool:=tTorch \WObj:=wobj0);
            points{i}.trans := [fields{4}, fields{5}, fields{6}];
            points{i}.rot := NOrient([fields{7}, fields{8}, fields{9}, fields{10}]);
        ENDFOR
        SocketClose sock;

        ! Move: kind 1 approach, 2 weld, 3 retract.
        FOR i FROM 1 TO count DO
            TEST kinds{i}
            CASE 1:
                MoveJ points{i}, v200, z5, tTorch;
            CASE 2:
                ! The first weld point is reached at a slow approach speed;
                ! arc on there (ArcLStart with the arc option), arc off at
                ! the last (ArcLEnd).
                MoveL points{i}, v10, fine, tTorch;
            CASE 3:
                MoveL points{i}, v200, z5, tTorch;
            ENDTEST
        ENDFOR
    ENDPROC

    ! Sends one line and receives its one reply line.
    PROC Ask(string line, INOUT string reply)
        SocketSend sock \Str:=line + "\0D\0A";
        SocketReceive sock \Str:=reply \Time:=60;
    ENDPROC

    ! An error line is -code,reason: show the reason and stop.
    PROC CheckOk(string reply)
        IF StrPart(reply, 1, 1) = "-" THEN
            ErrWrite "weldseam error", reply;
            SocketClose sock;
            Stop;
        ENDIF
    ENDPROC

    ! Reads the comma-separated numbers of a reply line into fields;
    ! returns how many. The line ends at CR LF.
    FUNC num Split(string line, INOUT num fields{*})
        VAR num start := 1;
        VAR num comma;
        VAR num k := 0;
        VAR num length;
        VAR bool ok;
        length := StrFind(line, 1, "\0D\0A") - 1;
        WHILE start <= length AND k < Dim(fields, 1) DO
            comma := StrFind(line, start, ",");
            IF comma > length THEN
                comma := length + 1;
            ENDIF
            k := k + 1;
            ok := StrToVal(StrPart(line, start, comma - start), fields{k});
            IF NOT ok THEN
                ErrWrite "weldseam", "cannot read a number in " + line;
                Stop;
            ENDIF
            start := comma + 1;
        ENDWHILE
        RETURN k;
    ENDFUNC
ENDMODULE
